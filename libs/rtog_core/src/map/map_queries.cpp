// The queries of the map: cells, boxes, rays, nearest obstacles, figures, the class cover.
#include <algorithm>
#include <cmath>
#include <limits>

#include "map/map_engine.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "storage/box_cover.hpp"

namespace rtog {
namespace {
const MapStore& covered(MapEngine& engine) {
  engine.ensureCovered();
  return engine.store;
}
}  // namespace

void OccupancyMap::visitLeaves(const Box* region, void* fn, LeafVisitor visit) const {
  const MapStore& store = covered(*engine_);
  if (region) {
    store.index.forEachLeafIn(*region, [&](const Box& b, float v) { visit(fn, b, v); });
  } else {
    store.index.forEachLeaf([&](const Box& b, float v) { visit(fn, b, v); });
  }
}

std::size_t OccupancyMap::leafCount() const { return covered(*engine_).index.leafCount(); }

Box OccupancyMap::keyBounds() const { return covered(*engine_).index.upper().bounds(); }

std::string OccupancyMap::checkInvariants() const { return covered(*engine_).checkInvariants(); }

std::optional<float> OccupancyMap::logOdds(const Key& k) const {
  const MapStore& store = covered(*engine_);
  const LeafEntry* e = store.index.findLeaf(k);
  if (!e) return std::nullopt;
  return e->value;
}

double OccupancyMap::occupancy(const Key& k) const {
  const auto l = logOdds(k);
  return probability(l ? *l : engine_->store.model.prior());
}

CellState OccupancyMap::state(const Key& k) const {
  const auto l = logOdds(k);
  return l ? engine_->store.model.classify(*l) : CellState::Unknown;
}

CellState OccupancyMap::stateAt(const Eigen::Vector3d& p) const {
  Key k;
  return engine_->store.lattice.tryKey(p, k) ? state(k) : CellState::Unknown;
}

BoxSummary OccupancyMap::summarize(const Box& b) const {
  const MapStore& store = covered(*engine_);
  BoxSummary s;
  std::int64_t known = 0;
  store.index.forEachLeafIn(b, [&](const Box& lb, float v) {
    const std::int64_t n = lb.intersection(b).volume();
    known += n;
    (store.model.classify(v) == CellState::Occupied ? s.occupied : s.free) += n;
  });
  s.unknown = b.volume() - known;
  return s;
}

OccupancyMap::RayHit OccupancyMap::castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                           double max_range) const {
  const MapStore& store = covered(*engine_);
  RayHit r;
  const double n = direction.norm();
  if (!(n > 0.0) || !std::isfinite(n) || !origin.allFinite() || !(max_range > 0.0)) return r;
  const Eigen::Vector3d o = store.lattice.toLattice(origin);
  const Eigen::Vector3d d = direction / n;
  const double t_max = std::isfinite(max_range) ? max_range / resolution() : std::numeric_limits<double>::max();
  // Leaf nodes arrive in order of where the ray enters their box; a node entered after the
  // best leaf found so far cannot hold a nearer one.
  double best_t = std::numeric_limits<double>::infinity();
  Box best_box;
  store.index.upper().firstAlongRay(o, d, t_max, [&](Handle h, const Box& node_box) {
    double t0 = 0.0, t1 = 0.0;
    intersectRay(o, d, t_max, node_box, t0, t1);
    if (t0 >= best_t) return true;
    store.index.forEachInLeafNode(h, [&](const Box& lb, float v) {
      if (store.model.classify(v) != CellState::Occupied) return;
      double a, b;
      if (intersectRay(o, d, t_max, lb, a, b) && a < best_t) best_t = a, best_box = lb;
    });
    return false;
  });
  if (!std::isfinite(best_t)) return r;
  const Eigen::Vector3d entry = o + d * best_t;
  for (int a = 0; a < 3; ++a)
    r.cell[a] = std::clamp(static_cast<std::int32_t>(std::floor(entry[a])), best_box.min[a], best_box.max[a]);
  r.hit = true;
  r.distance = best_t * resolution();
  return r;
}

OccupancyMap::NearestHit OccupancyMap::nearestOccupied(const Eigen::Vector3d& p, double max_distance) const {
  const MapStore& store = covered(*engine_);
  NearestHit r;
  if (!p.allFinite()) return r;
  const Eigen::Vector3d pl = store.lattice.toLattice(p);
  const double lim = max_distance / resolution();
  double best = std::isfinite(lim) ? lim * lim : std::numeric_limits<double>::infinity();
  bool found = false;
  store.index.upper().nearest(
      pl,
      [&](Handle h, const Box& node_box) {
        if (squaredDistance(pl, node_box) > best) return true;
        store.index.forEachInLeafNode(h, [&](const Box& lb, float v) {
          if (store.model.classify(v) != CellState::Occupied) return;
          const double d2 = squaredDistance(pl, lb);
          if (d2 < best || (!found && d2 <= best)) best = d2, r.leaf = lb, found = true;
        });
        return false;
      },
      best);
  if (!found) return r;
  r.found = true;
  r.distance = std::sqrt(best) * resolution();
  return r;
}

std::int64_t OccupancyMap::cellCount() const {
  const MapStore& store = covered(*engine_);
  std::int64_t n = 0;
  store.index.forEachLeaf([&](const Box& b, float) { n += b.volume(); });
  return n;
}

std::size_t OccupancyMap::memoryBytes() const { return sizeof(*this) + engine_->memoryBytes(); }

MapStatistics OccupancyMap::statistics() const {
  const MapStore& store = covered(*engine_);
  MapStatistics s;
  store.index.forEachLeaf([&](const Box& b, float v) {
    const bool occ = store.model.classify(v) == CellState::Occupied;
    ++(occ ? s.occupied_leaves : s.free_leaves);
    (occ ? s.occupied_cells : s.free_cells) += b.volume();
  });
  s.leaves = store.index.leafCount();
  s.cells = s.occupied_cells + s.free_cells;
  s.bricks = store.index.brickCount();
  s.tree_height = store.index.upper().height() + 1;
  s.tree_nodes = store.index.upper().nodeCount() + store.index.upper().size();
  s.memory_bytes = memoryBytes();
  s.bounds = store.index.upper().bounds();
  return s;
}

ClassCover OccupancyMap::classCover(const std::function<void(const Box&, CellState)>& emit) const {
  const MapStore& store = covered(*engine_);
  ClassCover counts;
  store.index.forEachBrick([&](const Brick& b) {
    BrickMask by_class[2] = {};  // free, occupied
    for (const LeafEntry& e : b.leaves) {
      BrickMask& m = by_class[store.model.classify(e.value) == CellState::Occupied ? 1 : 0];
      const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
      for (int z = e.lo[2]; z <= e.hi[2]; ++z)
        for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
          const int base = localIndex(0, y, z);
          m[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
        }
    }
    const Key o = brickOrigin(b.brick);
    for (const bool occupied : {false, true})
      detail::coverGreedily(
          by_class[occupied ? 1 : 0],
          [&](const std::uint8_t* lo, const std::uint8_t* hi, int) {
            ++(occupied ? counts.occupied : counts.free);
            if (emit)
              emit(Box{Key{o.x + lo[0], o.y + lo[1], o.z + lo[2]}, Key{o.x + hi[0], o.y + hi[1], o.z + hi[2]}},
                   occupied ? CellState::Occupied : CellState::Free);
          });
  });
  return counts;
}

}  // namespace rtog
