// OccupancyMap: the public face of MapEngine. Readers cover the planar cache first.
#include "rtog/core/occupancy_map.hpp"

#include "integrate/beam_integrator.hpp"
#include "integrate/cell_assignment.hpp"
#include "integrate/cone_integrator.hpp"
#include "integrate/pose_blur.hpp"
#include "map/map_engine.hpp"
#include "storage/brick.hpp"

namespace rtog {

OccupancyMap::OccupancyMap(const MapParams& params) : engine_(std::make_unique<MapEngine>(params)) {}

OccupancyMap::OccupancyMap(const OccupancyMap& other) {
  other.engine_->ensureCovered();
  engine_ = std::make_unique<MapEngine>(other.engine_->store);
}

OccupancyMap::OccupancyMap(OccupancyMap&& other) : engine_(std::make_unique<MapEngine>(other.params())) {
  *this = std::move(other);
}

OccupancyMap::~OccupancyMap() = default;

OccupancyMap& OccupancyMap::operator=(const OccupancyMap& other) {
  if (this != &other) {
    other.engine_->ensureCovered();
    engine_->clear();
    engine_->store = other.engine_->store;
  }
  return *this;
}

OccupancyMap& OccupancyMap::operator=(OccupancyMap&& other) {
  if (this != &other) {
    other.engine_->ensureCovered();
    engine_->clear();
    engine_->store = std::move(other.engine_->store);
    // The moved-from map: empty, with its parameters.
    other.engine_ = std::make_unique<MapEngine>(engine_->store.params);
  }
  return *this;
}

const MapParams& OccupancyMap::params() const { return engine_->store.params; }
const Lattice& OccupancyMap::lattice() const { return engine_->store.lattice; }
const LogOddsModel& OccupancyMap::logOddsModel() const { return engine_->store.model; }

void OccupancyMap::clear() { engine_->clear(); }

void OccupancyMap::setRegion(const Box& region) {
  MapStore& store = engine_->store;
  if (region.isEmpty()) {
    store.restricted = false;
    store.region = Box::empty();
    return;
  }
  const auto onBorders = [](const Key& k, int add) {
    for (int a = 0; a < 3; ++a)
      if (((k[a] + add) & (kBrickSize - 1)) != 0) return false;
    return true;
  };
  if (!keyInRange(region.min) || !keyInRange(region.max) || !onBorders(region.min, 0) || !onBorders(region.max, 1))
    throw std::invalid_argument("rtog::OccupancyMap::setRegion: the region must be whole bricks (faces on multiples of " +
                                std::to_string(kBrickSize) + " cells) within the key range");
  const Box bricks{brickOf(region.min), brickOf(region.max)};
  const Box bounds = keyBounds();
  if (!bounds.isEmpty() && !region.contains(bounds)) {
    bool outside = false;
    forEachLeaf([&](const Box& b, float) { outside = outside || !region.contains(b); });
    if (outside) throw std::logic_error("rtog::OccupancyMap::setRegion: the map holds cells outside the region");
  }
  store.restricted = true;
  store.region = bricks;
}

Box OccupancyMap::region() const {
  const MapStore& store = engine_->store;
  if (!store.restricted) return Box::empty();
  const Key lo = store.region.min, hi = store.region.max;
  const auto cells = [](std::int32_t b, int add) { return b * kBrickSize + add; };
  return Box{Key{cells(lo.x, 0), cells(lo.y, 0), cells(lo.z, 0)},
             Key{cells(hi.x, kBrickSize - 1), cells(hi.y, kBrickSize - 1), cells(hi.z, kBrickSize - 1)}};
}
InsertStats OccupancyMap::flush() { return engine_->flush(); }
bool OccupancyMap::hasPendingCover() const { return engine_->cover_pending.load(std::memory_order_acquire); }

// Each verb: its integrator, then the engine's apply (MapEngine::integrate).
InsertStats OccupancyMap::insertPointCloud(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                           std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  return engine_->integrate([&](const IntegrationContext& c) { return integrateScan(c, origin, points, count, ip, is_hit); });
}

InsertStats OccupancyMap::insertPointSource(const Eigen::Vector3d& origin, const PointSource& source,
                                           const InsertParams& ip) {
  return engine_->integrate([&](const IntegrationContext& c) { return integrateScan(c, origin, source, ip); });
}

InsertStats OccupancyMap::insertBlurred(const WeightedScan* scans, std::size_t n, const InsertParams& ip) {
  return engine_->integrate([&](const IntegrationContext& c) { return PoseBlurIntegrator(c).trace(scans, n, ip); });
}

InsertStats OccupancyMap::insertBlurred(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                        std::size_t count, const PoseMove* moves, std::size_t n,
                                        const InsertParams& ip, const std::uint8_t* is_hit) {
  return engine_->integrate(
      [&](const IntegrationContext& c) { return PoseBlurIntegrator(c).resample(origin, points, count, is_hit, moves, n, ip); });
}

InsertStats OccupancyMap::insertCones(const ConeReading* readings, std::size_t n, ConeWeighting w,
                                      const InsertParams& ip) {
  return engine_->integrate([&](const IntegrationContext& c) { return ConeIntegrator(c).trace(readings, n, w, ip); });
}

InsertStats OccupancyMap::applyStepRuns(std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                                        std::vector<float>* after) {
  return engine_->apply(UpdateSet::stepRuns(z, runs, n, rule, after));
}

InsertStats OccupancyMap::assignCells(const Box* boxes, const float* values, std::size_t n) {
  return engine_->integrate([&](const IntegrationContext& c) { return CellAssignment(c).trace(boxes, values, n); });
}

void OccupancyMap::releaseInsertBuffers() { rtog::releaseInsertBuffers(); }

}  // namespace rtog
