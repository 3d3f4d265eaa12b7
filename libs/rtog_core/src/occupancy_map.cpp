// Construction, queries and the invariant checker of the R-tree occupancy grid.
#include "rtog/core/occupancy_map.hpp"

#include <cmath>
#include <sstream>
#include <unordered_set>

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
  cells_occupied += o.cells_occupied;
  cells_free += o.cells_free;
  cells_unchanged += o.cells_unchanged;
  leaves_created += o.leaves_created;
  leaves_merged += o.leaves_merged;
  leaves_split += o.leaves_split;
  return *this;
}

static const MapParams& validated(const MapParams& p) {
  p.validate();
  return p;
}

OccupancyMap::OccupancyMap(const MapParams& params)
    : params_(validated(params)),
      lattice_(params.resolution),
      model_(params.log_odds),
      tree_(params.rtree),
      local_(kBrickCells, -1) {}

void OccupancyMap::clear() {
  tree_.clear();
  brick_index_.clear();
  bricks_.clear();
}

std::uint32_t OccupancyMap::brickSlot(const Key& brick) {
  const auto next = static_cast<std::uint32_t>(bricks_.size());
  const std::uint32_t slot = brick_index_.findOrInsert(packKey(brick), next);
  if (slot == next) bricks_.push_back(Brick{brick, {}});
  return slot;
}

const OccupancyMap::Brick* OccupancyMap::findBrick(const Key& brick) const {
  const std::uint32_t slot = brick_index_.find(packKey(brick));
  return slot == detail::FlatHashMap64::kAbsent ? nullptr : &bricks_[slot];
}

Box OccupancyMap::globalBox(const Brick& b, const BrickLeaf& l) const {
  const Key o = brickOrigin(b.brick);
  return Box{Key{o.x + l.lo[0], o.y + l.lo[1], o.z + l.lo[2]}, Key{o.x + l.hi[0], o.y + l.hi[1], o.z + l.hi[2]}};
}

Handle OccupancyMap::findLeaf(const Key& k) const {
  if (!keyInRange(k)) return kNoHandle;
  const Brick* b = findBrick(brickOf(k));
  if (!b) return kNoHandle;
  const Key l = localKey(localIndex(k));
  for (const BrickLeaf& leaf : b->leaves)
    if (l.x >= leaf.lo[0] && l.x <= leaf.hi[0] && l.y >= leaf.lo[1] && l.y <= leaf.hi[1] && l.z >= leaf.lo[2] &&
        l.z <= leaf.hi[2])
      return leaf.handle;
  return kNoHandle;
}

bool OccupancyMap::mergeable(float v) const {
  switch (params_.merge) {
    case MergePolicy::Off: return false;
    case MergePolicy::Clamped: return model_.isClamped(v);
    default: return true;
  }
}

std::optional<float> OccupancyMap::logOdds(const Key& k) const {
  const Handle h = findLeaf(k);
  if (h == kNoHandle) return std::nullopt;
  return tree_.payload(h);
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
  BoxSummary s;
  std::int64_t known = 0;
  tree_.queryBox(b, [&](Handle h, const Box& lb) {
    const std::int64_t n = lb.intersection(b).volume();
    known += n;
    (model_.classify(tree_.payload(h)) == CellState::Occupied ? s.occupied : s.free) += n;
  });
  s.unknown = b.volume() - known;
  return s;
}

OccupancyMap::RayHit OccupancyMap::castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                           double max_range) const {
  RayHit r;
  const double n = direction.norm();
  if (!(n > 0.0) || !std::isfinite(n) || !origin.allFinite() || !(max_range > 0.0)) return r;
  const Eigen::Vector3d o = lattice_.toLattice(origin);
  const Eigen::Vector3d d = direction / n;
  const double t_max = std::isfinite(max_range) ? max_range / resolution() : std::numeric_limits<double>::max();
  const auto hit = tree_.firstAlongRay(o, d, t_max, [&](Handle h, const Box&) {
    return model_.classify(tree_.payload(h)) == CellState::Occupied;
  });
  if (!hit) return r;
  const Box& b = tree_.box(hit.handle);
  const Eigen::Vector3d entry = o + d * hit.value;
  for (int a = 0; a < 3; ++a)
    r.cell[a] = std::clamp(static_cast<std::int32_t>(std::floor(entry[a])), b.min[a], b.max[a]);
  r.hit = true;
  r.distance = hit.value * resolution();
  return r;
}

OccupancyMap::NearestHit OccupancyMap::nearestOccupied(const Eigen::Vector3d& p, double max_distance) const {
  NearestHit r;
  if (!p.allFinite()) return r;
  const double lim = max_distance / resolution();
  const auto hit = tree_.nearest(
      lattice_.toLattice(p),
      [&](Handle h, const Box&) { return model_.classify(tree_.payload(h)) == CellState::Occupied; },
      std::isfinite(lim) ? lim * lim : std::numeric_limits<double>::infinity());
  if (!hit) return r;
  r.found = true;
  r.leaf = tree_.box(hit.handle);
  r.distance = std::sqrt(hit.value) * resolution();
  return r;
}

std::int64_t OccupancyMap::cellCount() const {
  std::int64_t n = 0;
  tree_.forEach([&](Handle, const Box& b) { n += b.volume(); });
  return n;
}

std::size_t OccupancyMap::memoryBytes() const {
  std::size_t bytes = sizeof(*this) + tree_.memoryBytes() + brick_index_.memoryBytes() +
                      bricks_.capacity() * sizeof(Brick) + local_.capacity() * sizeof(std::int32_t);
  for (const Brick& b : bricks_) bytes += b.leaves.capacity() * sizeof(BrickLeaf);
  return bytes;
}

MapStatistics OccupancyMap::statistics() const {
  MapStatistics s;
  tree_.forEach([&](Handle h, const Box& b) {
    const bool occ = model_.classify(tree_.payload(h)) == CellState::Occupied;
    ++(occ ? s.occupied_leaves : s.free_leaves);
    (occ ? s.occupied_cells : s.free_cells) += b.volume();
  });
  s.leaves = tree_.size();
  s.cells = s.occupied_cells + s.free_cells;
  s.bricks = bricks_.size();
  s.tree_height = tree_.height();
  s.tree_nodes = tree_.nodeCount();
  s.memory_bytes = memoryBytes();
  s.bounds = tree_.bounds();
  return s;
}

std::string OccupancyMap::checkInvariants() const {
  std::string err = tree_.checkInvariants(true);
  if (!err.empty()) return "R-tree: " + err;
  std::size_t leaves = 0;
  std::unordered_set<Handle> seen;
  for (const Brick& b : bricks_) {
    if (brick_index_.find(packKey(b.brick)) != static_cast<std::uint32_t>(&b - bricks_.data()))
      return "brick index does not point at brick " + toString(b.brick);
    for (const BrickLeaf& l : b.leaves) {
      ++leaves;
      for (int a = 0; a < 3; ++a)
        if (l.lo[a] > l.hi[a] || l.hi[a] >= kBrickSize) return "malformed brick leaf in brick " + toString(b.brick);
      if (!tree_.valid(l.handle)) return "brick leaf with a dead handle";
      if (!seen.insert(l.handle).second) return "handle listed twice in the brick index";
      const Box gb = globalBox(b, l);
      if (tree_.box(l.handle) != gb)
        return "brick leaf " + toString(gb) + " differs from its tree entry " + toString(tree_.box(l.handle));
      const float v = tree_.payload(l.handle);
      if (!(v >= model_.clampMin() && v <= model_.clampMax())) return "leaf value outside the clamping bounds";
      if (gb.volume() > 1 && !mergeable(v)) return "merged leaf " + toString(gb) + " holds a value its policy does not merge";
    }
  }
  if (leaves != tree_.size()) return "brick index and tree disagree on the number of leaves";
  return {};
}

}  // namespace rtog
