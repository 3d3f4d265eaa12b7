// rtog::CRTreeOccupancyGridMap: construction, registration with MRPT, the map-wide state (the
// .ini options are in _options.cpp).
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

#include <stdexcept>

#include <mrpt/rtti/CObject.h>

#include "mrpt_grid.hpp"
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/register_classes.h"
#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "CRTreeOccupancyGridMap_caches.hpp"

using namespace mrpt::maps;

IMPLEMENTS_SERIALIZABLE(CRTreeOccupancyGridMap, CMetricMap, rtog)

MAP_DEFINITION_REGISTER("rtog::CRTreeOccupancyGridMap,rtreeOccupancyGrid", rtog::CRTreeOccupancyGridMap)

// MAP_DEFINITION_REGISTER makes CMultiMetricMap able to create the map from an .ini; the RTTI
// registration lets CArchive deserialize it (rbpf-slam copies maps through serialization). It
// is a variable defined after IMPLEMENTS_SERIALIZABLE, not MRPT_INITIALIZER: see
// register_classes.cpp.
namespace {
[[maybe_unused]] const bool registered_at_load =
    (mrpt::rtti::registerClass(CLASS_ID(rtog::CRTreeOccupancyGridMap)), true);
}  // namespace

namespace rtog {

// ---- the map -----------------------------------------------------------------------------

CRTreeOccupancyGridMap::CRTreeOccupancyGridMap(double resolution)
    : map_(insertionOptions.toMapParams(resolution)) {
  registerMrptClasses();  // a process that makes a map can read one back (see above)
  setGridFrame(-10, 10, -10, 10);
}

namespace {
// toMapParams() quantizes the probabilities as MRPT does (float to int casts): only valid ones
// may reach it, or a NaN is undefined behaviour before validate() could refuse it.
const CRTreeOccupancyGridMap::TInsertionOptions& validated(const CRTreeOccupancyGridMap::TInsertionOptions& io) {
  io.validate();
  return io;
}
}  // namespace

CRTreeOccupancyGridMap::CRTreeOccupancyGridMap(double resolution, const TInsertionOptions& io)
    : insertionOptions(io), map_(validated(io).toMapParams(resolution)) {
  registerMrptClasses();
  setGridFrame(-10, 10, -10, 10);
}

void CRTreeOccupancyGridMap::syncParams() {
  insertionOptions.validate();
  const MapParams want = insertionOptions.toMapParams(map_.resolution());
  const MapParams& have = map_.params();
  const LogOddsParams &a = want.log_odds, &b = have.log_odds;
  const bool same = a.prob_hit == b.prob_hit && a.prob_miss == b.prob_miss && a.clamp_min == b.clamp_min &&
                    a.clamp_max == b.clamp_max && a.occupied_threshold == b.occupied_threshold &&
                    a.prior == b.prior && want.merge == have.merge;
  if (same) return;
  if (map_.leafCount() != 0)
    throw std::logic_error(
        "rtog::CRTreeOccupancyGridMap: insertionOptions (probabilities, clamping or mergePolicy) changed "
        "while the map holds cells; call clear() first");
  MapParams p = want;
  p.rtree = have.rtree;
  map_ = OccupancyMap(p);
  notifyMapChanged();
}

void CRTreeOccupancyGridMap::notifyMapChanged() {
  std::lock_guard<std::mutex> lk(caches_->mutex);
  caches_->dropCellData();
  caches_->tiles.reset();
}

InsertStats CRTreeOccupancyGridMap::fuse(const CRTreeOccupancyGridMap& other, const mrpt::poses::CPose3D& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = pose.getRotationMatrix().asEigen();
  t.translation() = Eigen::Vector3d(pose.x(), pose.y(), pose.z());
  const InsertStats st = map_.fuse(other.map_, t, insertionOptions.threads > 0 ? insertionOptions.threads : defaultThreadCount());
  notifyMapChanged();
  return st;
}

void CRTreeOccupancyGridMap::internal_clear() {
  if (prior_) {
    map_ = prior_->map;
    frame_ = prior_->frame;
  } else {
    map_.clear();
    setGridFrame(-10, 10, -10, 10);  // as COccupancyGridMap2D::clear()
    // As COccupancyGridMap3D::clear(): its default extent at the grid's resolution.
    if (frame3d_.defined)
      setGridFrame3D(mrpt::math::TPoint3D(-5, -5, -5), mrpt::math::TPoint3D(5, 5, 5),
                     static_cast<float>(frame3d_.resolution));
  }
  lastInsertStats = InsertStats{};
  totalInsertStats = InsertStats{};
  invalidRangesSkipped = 0;
  notifyMapChanged();
  std::lock_guard<std::mutex> lk(caches_->mutex);
  caches_->local_valid = false;
}

bool CRTreeOccupancyGridMap::isEmpty() const { return map_.leafCount() == 0; }

const mrpt::maps::CSimplePointsMap& CRTreeOccupancyGridMap::occupiedCellCenters() const {
  std::lock_guard<std::mutex> lk(caches_->mutex);
  if (caches_->points_dirty) {
    auto& pts = caches_->occupied_points;
    pts.clear();
    const LogOddsModel& lm = map_.logOddsModel();
    const Lattice& lat = map_.lattice();
    map_.forEachLeaf([&](const Box& b, float v) {
      if (lm.classify(v) != CellState::Occupied) return;
      forEachCell(b, [&](const Key& k) {
        const Eigen::Vector3d c = lat.cellCenter(k);
        pts.insertPointFast(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()));
      });
    });
    pts.mark_as_modified();
    caches_->points_dirty = false;
  }
  return caches_->occupied_points;
}

std::string CRTreeOccupancyGridMap::asString() const {
  const MapStatistics s = map_.statistics();
  std::ostringstream os;
  os << "rtog::CRTreeOccupancyGridMap: resolution " << map_.resolution() << " m, " << s.leaves << " leaves ("
     << s.occupied_leaves << " occupied), " << s.cells << " cells (" << s.occupied_cells << " occupied, "
     << s.free_cells << " free), " << s.memory_bytes << " bytes";
  return os.str();
}

}  // namespace rtog
