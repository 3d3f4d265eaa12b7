// 3D frontiers from the free leaves' faces (rtog/core/explore.hpp): for each face of a free leaf,
// the slab of cells just outside it, minus the footprints of the leaves that meet the slab, is
// unknown; the leaf's layer of cells under that remainder is frontier. One R-tree query per free
// leaf (its box grown by a cell) finds every neighbour of its six faces.
#include <algorithm>
#include <array>

#include "explore/frontier.hpp"

namespace rtog::explore_detail {
namespace {

/// [u0, u1] x [v0, v1], inclusive, on the two axes of a face.
struct Rect {
  std::int32_t u0, v0, u1, v1;
};

/// rects minus cut, each rect split into at most four.
void subtract(std::vector<Rect>& rects, const Rect& cut, std::vector<Rect>& out) {
  out.clear();
  for (const Rect& r : rects) {
    if (cut.u1 < r.u0 || cut.u0 > r.u1 || cut.v1 < r.v0 || cut.v0 > r.v1) {
      out.push_back(r);
      continue;
    }
    if (r.v0 < cut.v0) out.push_back(Rect{r.u0, r.v0, r.u1, cut.v0 - 1});
    if (r.v1 > cut.v1) out.push_back(Rect{r.u0, cut.v1 + 1, r.u1, r.v1});
    const std::int32_t v0 = std::max(r.v0, cut.v0), v1 = std::min(r.v1, cut.v1);
    if (r.u0 < cut.u0) out.push_back(Rect{r.u0, v0, cut.u0 - 1, v1});
    if (r.u1 > cut.u1) out.push_back(Rect{cut.u1 + 1, v0, r.u1, v1});
  }
  rects.swap(out);
}

/// `a` minus the boxes `cuts`, as disjoint boxes appended to `out`.
void subtractBoxes(const Box& a, const std::vector<Box>& cuts, std::vector<Box>& out) {
  std::vector<Box> rest{a}, next;
  for (const Box& c : cuts) {
    next.clear();
    for (const Box& r : rest) {
      if (!r.intersects(c)) {
        next.push_back(r);
        continue;
      }
      Box m = r;  // what is left of r to split, axis by axis
      for (int ax = 0; ax < 3; ++ax) {
        if (m.min[ax] < c.min[ax]) {
          Box piece = m;
          piece.max[ax] = c.min[ax] - 1;
          next.push_back(piece);
          m.min[ax] = c.min[ax];
        }
        if (m.max[ax] > c.max[ax]) {
          Box piece = m;
          piece.min[ax] = c.max[ax] + 1;
          next.push_back(piece);
          m.max[ax] = c.max[ax];
        }
      }
    }
    rest.swap(next);
  }
  out.insert(out.end(), rest.begin(), rest.end());
}

}  // namespace

void frontier3D(const OccupancyMap& map, std::vector<FrontierPiece>& pieces, std::vector<Box>& boxes) {
  const float occ = map.logOddsModel().occupiedThreshold();
  std::vector<Box> free_leaves;
  map.forEachLeaf([&](const Box& b, float v) {
    if (v < occ) free_leaves.push_back(b);
  });
  std::vector<Box> near, own;
  std::vector<Rect> rest, scratch;
  for (const Box& leaf : free_leaves) {
    Box grown = leaf;
    for (int ax = 0; ax < 3; ++ax) {
      grown.min[ax] = std::max(kKeyMin, grown.min[ax] - 1);
      grown.max[ax] = std::min(kKeyMax, grown.max[ax] + 1);
    }
    near.clear();
    map.forEachLeafIn(grown, [&](const Box& b, float) {
      if (b != leaf) near.push_back(b);
    });
    own.clear();
    for (int ax = 0; ax < 3; ++ax) {
      const int u = (ax + 1) % 3, w = (ax + 2) % 3;
      for (const int dir : {-1, 1}) {
        const std::int64_t outside = dir > 0 ? std::int64_t{leaf.max[ax]} + 1 : std::int64_t{leaf.min[ax]} - 1;
        if (outside < kKeyMin || outside > kKeyMax) continue;  // beyond the keys: not unknown space
        rest.assign(1, Rect{leaf.min[u], leaf.min[w], leaf.max[u], leaf.max[w]});
        for (const Box& n : near) {
          if (n.min[ax] > outside || n.max[ax] < outside) continue;
          subtract(rest, Rect{n.min[u], n.min[w], n.max[u], n.max[w]}, scratch);
          if (rest.empty()) break;
        }
        for (const Rect& r : rest) {
          Box cells;
          cells.min[ax] = cells.max[ax] = dir > 0 ? leaf.max[ax] : leaf.min[ax];
          cells.min[u] = r.u0, cells.max[u] = r.u1;
          cells.min[w] = r.v0, cells.max[w] = r.v1;
          Eigen::Vector3d normal = Eigen::Vector3d::Zero();
          normal[ax] = double(dir) * double(cells.volume());
          pieces.push_back(FrontierPiece{cells, normal});
          // The leaf's cells of this face not yet taken by its other faces.
          const std::size_t first = boxes.size();
          subtractBoxes(cells, own, boxes);
          own.insert(own.end(), boxes.begin() + static_cast<std::ptrdiff_t>(first), boxes.end());
        }
      }
    }
  }
}

}  // namespace rtog::explore_detail
