// frontierCells and frontierRegions (rtog/core/explore.hpp): the finders' boxes in a fixed order,
// grouped by union-find over a hash of 16-cell buckets (boxes whose grown boxes meet are joined).
#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "explore/frontier.hpp"
#include "rtog/core/band.hpp"

namespace rtog {
namespace {

void find(const OccupancyMap& map, const FrontierOptions& o, std::vector<explore_detail::FrontierPiece>& pieces,
          std::vector<Box>& boxes) {
  if (!(o.min_z <= o.max_z)) throw std::invalid_argument("rtog::frontiers: need min_z <= max_z");
  if (o.min_region_cells < 1) throw std::invalid_argument("rtog::frontiers: min_region_cells must be at least 1");
  if (o.planar) {
    const Box kb = map.keyBounds();
    if (kb.isEmpty()) return;
    explore_detail::frontier2D(map, bandRegion(map, kb, o.min_z, o.max_z), pieces, boxes);
  } else {
    explore_detail::frontier3D(map, pieces, boxes);
  }
  std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.min < b.min; });
}

struct UnionFind {
  std::vector<std::uint32_t> up;
  explicit UnionFind(std::size_t n) : up(n) { std::iota(up.begin(), up.end(), 0u); }
  std::uint32_t root(std::uint32_t i) {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = root(a), b = root(b);
    if (a != b) up[std::max(a, b)] = std::min(a, b);
  }
};

/// Boxes by the 16-cell buckets they meet (planar boxes: z ignored, all share the band).
class Buckets {
 public:
  Buckets(const std::vector<Box>& boxes, bool planar) : boxes_(boxes), planar_(planar) {
    for (std::uint32_t i = 0; i < boxes.size(); ++i) forBuckets(boxes[i], [&](std::uint64_t k) { map_[k].push_back(i); });
  }
  template <class Fn>
  void forEachNear(const Box& b, Fn&& fn) const {
    Box g = b;
    for (int a = 0; a < 3; ++a) g.min[a] = std::max(kKeyMin, g.min[a] - 1), g.max[a] = std::min(kKeyMax, g.max[a] + 1);
    forBuckets(g, [&](std::uint64_t k) {
      const auto it = map_.find(k);
      if (it == map_.end()) return;
      for (const std::uint32_t j : it->second)
        if (boxes_[j].intersects(g)) fn(j);
    });
  }

 private:
  template <class Fn>
  void forBuckets(const Box& b, Fn&& fn) const {
    const auto bucket = [](std::int32_t v) { return static_cast<std::uint64_t>((v - kKeyMin) >> 4); };
    const std::uint64_t z0 = planar_ ? 0 : bucket(b.min.z), z1 = planar_ ? 0 : bucket(b.max.z);
    for (std::uint64_t z = z0; z <= z1; ++z)
      for (std::uint64_t y = bucket(b.min.y); y <= bucket(b.max.y); ++y)
        for (std::uint64_t x = bucket(b.min.x); x <= bucket(b.max.x); ++x) fn(x | y << 21 | z << 42);
  }
  const std::vector<Box>& boxes_;
  bool planar_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> map_;
};

}  // namespace

std::vector<Box> frontierCells(const OccupancyMap& map, const FrontierOptions& options) {
  std::vector<explore_detail::FrontierPiece> pieces;
  std::vector<Box> boxes;
  find(map, options, pieces, boxes);
  return boxes;
}

std::vector<FrontierRegion> frontierRegions(const OccupancyMap& map, const FrontierOptions& options) {
  std::vector<explore_detail::FrontierPiece> pieces;
  std::vector<Box> boxes;
  find(map, options, pieces, boxes);
  const Buckets buckets(boxes, options.planar);
  UnionFind groups(boxes.size());
  for (std::uint32_t i = 0; i < boxes.size(); ++i) buckets.forEachNear(boxes[i], [&](std::uint32_t j) { groups.join(i, j); });
  // Regions numbered by their first box.
  std::vector<std::int64_t> region_of(boxes.size(), -1);
  std::vector<FrontierRegion> regions;
  const double res = map.resolution();
  for (std::uint32_t i = 0; i < boxes.size(); ++i) {
    const std::uint32_t r = groups.root(i);
    if (region_of[r] < 0) region_of[r] = static_cast<std::int64_t>(regions.size()), regions.emplace_back();
    FrontierRegion& g = regions[static_cast<std::size_t>(region_of[r])];
    const Box& b = boxes[i];
    const std::int64_t n = options.planar ? b.extent(0) : b.volume();
    g.boxes.push_back(b);
    g.cells += n;
    Eigen::Vector3d centre;
    for (int a = 0; a < 3; ++a) centre[a] = (0.5 * (double(b.min[a]) + double(b.max[a])) + 0.5) * res;
    if (options.planar) centre.z() = 0.5 * (options.min_z + options.max_z);
    g.centroid += centre * double(n);
  }
  for (const explore_detail::FrontierPiece& p : pieces) {
    std::int64_t at = -1;
    buckets.forEachNear(Box::cell(p.cells.min), [&](std::uint32_t j) {
      if (at < 0 && boxes[j].contains(p.cells.min)) at = region_of[groups.root(j)];
    });
    if (at >= 0) regions[static_cast<std::size_t>(at)].normal += p.normal;
  }
  for (FrontierRegion& g : regions) {
    g.centroid /= double(g.cells);
    const double len = g.normal.norm();
    g.normal = len > 0 ? Eigen::Vector3d(g.normal / len) : Eigen::Vector3d::Zero();
  }
  regions.erase(std::remove_if(regions.begin(), regions.end(),
                               [&](const FrontierRegion& g) { return g.cells < options.min_region_cells; }),
                regions.end());
  std::stable_sort(regions.begin(), regions.end(), [](const FrontierRegion& a, const FrontierRegion& b) { return a.cells > b.cells; });
  return regions;
}

}  // namespace rtog
