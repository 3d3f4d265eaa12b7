// Construction, queries and the invariant checker of the R-tree occupancy grid.
#include "rtog/core/occupancy_map.hpp"

#include "rtog/core/detail/cover.hpp"

#include <cmath>
#include <sstream>

namespace rtog {

const char* toString(SensorModel m) { return m == SensorModel::BeamBased ? "beam" : "endpoint"; }

const char* toString(MergePolicy m) {
  switch (m) {
    case MergePolicy::Off: return "off";
    case MergePolicy::Clamped: return "clamped";
    default: return "equal";
  }
}

SensorModel sensorModelFromString(const std::string& s) {
  if (s == "beam" || s == "beam_based" || s == "BeamBased") return SensorModel::BeamBased;
  if (s == "endpoint" || s == "beam_end_point" || s == "BeamEndPoint") return SensorModel::BeamEndPoint;
  throw std::invalid_argument("unknown sensor model '" + s + "' (expected 'beam' or 'endpoint')");
}

MergePolicy mergePolicyFromString(const std::string& s) {
  if (s == "off" || s == "false" || s == "0") return MergePolicy::Off;
  if (s == "clamped" || s == "true" || s == "1") return MergePolicy::Clamped;
  if (s == "equal") return MergePolicy::Equal;
  throw std::invalid_argument("unknown merge policy '" + s + "' (expected 'off', 'clamped' or 'equal')");
}

void MapParams::validate() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution) || resolution < 1e-4 || resolution > 1e3)
    throw std::invalid_argument("MapParams: resolution must lie in [1e-4, 1e3] m, got " + std::to_string(resolution));
  log_odds.validate();
  rtree.validate();
}

InsertStats& InsertStats::operator+=(const InsertStats& o) {
  rays_hit += o.rays_hit;
  rays_truncated += o.rays_truncated;
  skipped_non_finite += o.skipped_non_finite;
  skipped_zero_length += o.skipped_zero_length;
  skipped_out_of_range += o.skipped_out_of_range;
  skipped_too_long += o.skipped_too_long;
  cells_occupied += o.cells_occupied;
  cells_free += o.cells_free;
  cells_unchanged += o.cells_unchanged;
  leaves_created += o.leaves_created;
  leaves_merged += o.leaves_merged;
  leaves_split += o.leaves_split;
  return *this;
}

bool InsertStats::operator==(const InsertStats& o) const {
  return rays_hit == o.rays_hit && rays_truncated == o.rays_truncated && skipped_non_finite == o.skipped_non_finite &&
         skipped_zero_length == o.skipped_zero_length && skipped_out_of_range == o.skipped_out_of_range &&
         skipped_too_long == o.skipped_too_long &&
         cells_occupied == o.cells_occupied && cells_free == o.cells_free && cells_unchanged == o.cells_unchanged &&
         leaves_created == o.leaves_created && leaves_merged == o.leaves_merged && leaves_split == o.leaves_split;
}

static const MapParams& validated(const MapParams& p) {
  p.validate();
  return p;
}

OccupancyMap::OccupancyMap(const MapParams& params)
    : params_(validated(params)),
      lattice_(params.resolution),
      model_(params.log_odds),
      upper_(params.rtree),
      local_(kBrickCells, -1) {}

OccupancyMap::OccupancyMap(const OccupancyMap& other)
    : params_(other.params_), lattice_(other.lattice_), model_(other.model_), upper_(other.params_.rtree) {
  *this = other;
}

OccupancyMap::OccupancyMap(OccupancyMap&& other)
    : params_(other.params_), lattice_(other.lattice_), model_(other.model_), upper_(other.params_.rtree) {
  *this = std::move(other);
}

template <class Other>
void OccupancyMap::assignCovered(Other&& other) {
  other.ensureCovered();
  clear();
  params_ = other.params_;
  lattice_ = other.lattice_;
  model_ = other.model_;
  upper_ = std::forward<Other>(other).upper_;  // each member moved at most once
  brick_index_ = std::forward<Other>(other).brick_index_;
  bricks_ = std::forward<Other>(other).bricks_;
  leaf_count_ = other.leaf_count_;
}

OccupancyMap& OccupancyMap::operator=(const OccupancyMap& other) {
  if (this != &other) assignCovered(other);
  return *this;
}

OccupancyMap& OccupancyMap::operator=(OccupancyMap&& other) {
  if (this != &other) {
    assignCovered(std::move(other));
    other.clear();
  }
  return *this;
}

void OccupancyMap::clear() {
  upper_.clear();
  brick_index_.clear();
  bricks_.clear();
  leaf_count_ = 0;
  planar_layers_.clear();
  planar_index_.clear();
  recent_layers_.clear();
  cover_pending_.store(false, std::memory_order_release);
}

std::uint32_t OccupancyMap::brickSlot(const Key& brick) {
  const auto next = static_cast<std::uint32_t>(bricks_.size());
  const std::uint32_t slot = brick_index_.findOrInsert(packKey(brick), next);
  if (slot == next) bricks_.push_back(Brick{brick, {}, {}});
  return slot;
}

const OccupancyMap::Brick* OccupancyMap::findBrick(const Key& brick) const {
  const std::uint32_t slot = brick_index_.find(packKey(brick));
  return slot == detail::FlatHashMap64::kAbsent ? nullptr : &bricks_[slot];
}

Box OccupancyMap::leafNodeBox(const Brick& b, std::size_t node) const {
  if (node * leafNodeSize() >= b.leaves.size()) return Box::empty();
  return globalBox(brickOrigin(b.brick), localNodeBox(b.leaves, node));
}

OccupancyMap::LeafEntry OccupancyMap::localNodeBox(const std::vector<LeafEntry>& leaves, std::size_t node) const {
  // In brick-local bytes, one conversion at the end.
  const std::size_t first = node * leafNodeSize(), last = std::min(leaves.size(), first + leafNodeSize());
  LeafEntry united = leaves[first];
  for (std::size_t i = first + 1; i < last; ++i)
    for (int a = 0; a < 3; ++a) {
      united.lo[a] = std::min(united.lo[a], leaves[i].lo[a]);
      united.hi[a] = std::max(united.hi[a], leaves[i].hi[a]);
    }
  return united;
}

const OccupancyMap::LeafEntry* OccupancyMap::findLeaf(const Key& k) const {
  if (!keyInRange(k)) return nullptr;
  const Brick* b = findBrick(brickOf(k));
  if (!b) return nullptr;
  const Key l = localKey(localIndex(k));
  // Leaf-node boxes first, then the entries of the one node that can hold the cell.
  for (std::size_t n = 0; n < b->nodes.size(); ++n) {
    if (!upper_.box(b->nodes[n]).contains(k)) continue;
    const std::size_t first = n * leafNodeSize(), last = std::min(b->leaves.size(), first + leafNodeSize());
    for (std::size_t i = first; i < last; ++i) {
      const LeafEntry& e = b->leaves[i];
      if (l.x >= e.lo[0] && l.x <= e.hi[0] && l.y >= e.lo[1] && l.y <= e.hi[1] && l.z >= e.lo[2] && l.z <= e.hi[2])
        return &e;
    }
  }
  return nullptr;
}

bool OccupancyMap::mergeable(float v) const {
  switch (params_.merge) {
    case MergePolicy::Off: return false;
    case MergePolicy::Clamped: return model_.isClamped(v);
    default: return true;
  }
}

std::optional<float> OccupancyMap::logOdds(const Key& k) const {
  ensureCovered();
  const LeafEntry* e = findLeaf(k);
  if (!e) return std::nullopt;
  return e->value;
}

double OccupancyMap::occupancy(const Key& k) const {
  const auto l = logOdds(k);
  return probability(l ? *l : model_.prior());
}

CellState OccupancyMap::state(const Key& k) const {
  const auto l = logOdds(k);
  return l ? model_.classify(*l) : CellState::Unknown;
}

CellState OccupancyMap::stateAt(const Eigen::Vector3d& p) const {
  Key k;
  return lattice_.tryKey(p, k) ? state(k) : CellState::Unknown;
}

BoxSummary OccupancyMap::summarize(const Box& b) const {
  ensureCovered();
  BoxSummary s;
  std::int64_t known = 0;
  forEachLeafIn(b, [&](const Box& lb, float v) {
    const std::int64_t n = lb.intersection(b).volume();
    known += n;
    (model_.classify(v) == CellState::Occupied ? s.occupied : s.free) += n;
  });
  s.unknown = b.volume() - known;
  return s;
}

OccupancyMap::RayHit OccupancyMap::castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                           double max_range) const {
  ensureCovered();
  RayHit r;
  const double n = direction.norm();
  if (!(n > 0.0) || !std::isfinite(n) || !origin.allFinite() || !(max_range > 0.0)) return r;
  const Eigen::Vector3d o = lattice_.toLattice(origin);
  const Eigen::Vector3d d = direction / n;
  const double t_max = std::isfinite(max_range) ? max_range / resolution() : std::numeric_limits<double>::max();
  // Leaf nodes arrive in order of where the ray enters their box; a node entered after the
  // best leaf found so far cannot hold a nearer one.
  double best_t = std::numeric_limits<double>::infinity();
  Box best_box;
  upper_.firstAlongRay(o, d, t_max, [&](Handle h, const Box& node_box) {
    double t0 = 0.0, t1 = 0.0;
    intersectRay(o, d, t_max, node_box, t0, t1);
    if (t0 >= best_t) return true;
    forEachInLeafNode(h, [&](const Box& lb, float v) {
      if (model_.classify(v) != CellState::Occupied) return;
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
  ensureCovered();
  NearestHit r;
  if (!p.allFinite()) return r;
  const Eigen::Vector3d pl = lattice_.toLattice(p);
  const double lim = max_distance / resolution();
  double best = std::isfinite(lim) ? lim * lim : std::numeric_limits<double>::infinity();
  bool found = false;
  upper_.nearest(
      pl,
      [&](Handle h, const Box& node_box) {
        if (squaredDistance(pl, node_box) > best) return true;
        forEachInLeafNode(h, [&](const Box& lb, float v) {
          if (model_.classify(v) != CellState::Occupied) return;
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
  ensureCovered();
  std::int64_t n = 0;
  forEachLeaf([&](const Box& b, float) { n += b.volume(); });
  return n;
}

std::size_t OccupancyMap::memoryBytes() const {
  std::size_t bytes = sizeof(*this) + upper_.memoryBytes() + brick_index_.memoryBytes() +
                      bricks_.capacity() * sizeof(Brick) + local_.capacity() * sizeof(std::int32_t);
  for (const Brick& b : bricks_) bytes += b.leaves.capacity() * sizeof(LeafEntry) + b.nodes.heapBytes();
  return bytes + planar_layers_.capacity() * sizeof(PlanarLayer) + planar_index_.memoryBytes();
}

MapStatistics OccupancyMap::statistics() const {
  ensureCovered();
  MapStatistics s;
  forEachLeaf([&](const Box& b, float v) {
    const bool occ = model_.classify(v) == CellState::Occupied;
    ++(occ ? s.occupied_leaves : s.free_leaves);
    (occ ? s.occupied_cells : s.free_cells) += b.volume();
  });
  s.leaves = leaf_count_;
  s.cells = s.occupied_cells + s.free_cells;
  s.bricks = bricks_.size();
  s.tree_height = upper_.height() + 1;
  s.tree_nodes = upper_.nodeCount() + upper_.size();
  s.memory_bytes = memoryBytes();
  s.bounds = upper_.bounds();
  return s;
}

ClassCover OccupancyMap::classCover(const std::function<void(const Box&, CellState)>& emit) const {
  ensureCovered();
  ClassCover counts;
  for (const Brick& b : bricks_) {
    detail::BrickMask by_class[2] = {};  // free, occupied
    for (const LeafEntry& e : b.leaves) {
      detail::BrickMask& m = by_class[model_.classify(e.value) == CellState::Occupied ? 1 : 0];
      const std::uint64_t run = detail::xRun(e.lo[0], e.hi[0]);
      for (int z = e.lo[2]; z <= e.hi[2]; ++z)
        for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
          const int base = detail::localIdx(0, y, z);
          m[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
        }
    }
    const Key o = brickOrigin(b.brick);
    for (const bool occupied : {false, true})
      detail::coverGreedily(
          by_class[occupied ? 1 : 0], [](int, int) { return true; },
          [&](const std::uint8_t* lo, const std::uint8_t* hi, int) {
            ++(occupied ? counts.occupied : counts.free);
            if (emit)
              emit(Box{Key{o.x + lo[0], o.y + lo[1], o.z + lo[2]}, Key{o.x + hi[0], o.y + hi[1], o.z + hi[2]}},
                   occupied ? CellState::Occupied : CellState::Free);
          });
  }
  return counts;
}

std::string OccupancyMap::checkInvariants() const {
  ensureCovered();
  // Leaf-node boxes may overlap (inner boxes of an R-tree); leaves may not, checked below.
  std::string err = upper_.checkInvariants(false);
  if (!err.empty()) return "R-tree: " + err;
  std::size_t leaves = 0, nodes = 0;
  std::vector<std::uint8_t> painted(kBrickCells);
  for (std::size_t slot = 0; slot < bricks_.size(); ++slot) {
    const Brick& b = bricks_[slot];
    if (brick_index_.find(packKey(b.brick)) != slot) return "brick index does not point at brick " + toString(b.brick);
    const std::size_t want_nodes = (b.leaves.size() + leafNodeSize() - 1) / leafNodeSize();
    if (b.nodes.size() != want_nodes) return "brick " + toString(b.brick) + " has the wrong number of leaf nodes";
    for (std::size_t n = 0; n < b.nodes.size(); ++n) {
      const Handle h = b.nodes[n];
      if (!upper_.valid(h)) return "leaf node with a dead handle";
      const LeafNodeRef r = upper_.payload(h);
      if (r.brick != slot || r.node != n) return "leaf node reference mismatch";
      if (upper_.box(h) != leafNodeBox(b, n)) return "leaf node box is not the tight union of its entries";
    }
    nodes += b.nodes.size();
    std::fill(painted.begin(), painted.end(), 0);
    for (const LeafEntry& e : b.leaves) {
      ++leaves;
      for (int a = 0; a < 3; ++a)
        if (e.lo[a] > e.hi[a] || e.hi[a] >= kBrickSize) return "malformed leaf in brick " + toString(b.brick);
      const Box gb = globalBox(brickOrigin(b.brick), e);
      if (!(e.value >= model_.clampMin() && e.value <= model_.clampMax())) return "leaf value outside the clamping bounds";
      if (gb.volume() > 1 && !mergeable(e.value))
        return "merged leaf " + toString(gb) + " holds a value its policy does not merge";
      bool overlap = false;
      forEachCell(gb, [&](const Key& k) { overlap |= painted[localIndex(k)]++ != 0; });
      if (overlap) return "leaves overlap at " + toString(gb);
    }
  }
  if (leaves != leaf_count_) return "leaf count mismatch";
  if (nodes != upper_.size()) return "upper tree and bricks disagree on the number of leaf nodes";
  return {};
}

}  // namespace rtog
