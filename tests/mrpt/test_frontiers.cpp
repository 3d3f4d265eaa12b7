// Frontiers and the occupancy field (rtog/core/explore.hpp) on real maps: SENA (2D scans), the
// Malaga simplemap and TUM depth frames, at every merge policy. The frontier cells found from
// leaf faces equal the free cells (columns of a band in 2D) with an unknown face neighbour found
// cell by cell; the regions equal the connected components of those cells, with the same sizes
// and mean normals; O(x) equals each cell's value at its centre, is continuous across cell and
// cuboid faces and its gradient equals finite differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <random>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "registration_helpers.hpp"
#include "rtog/core/explore.hpp"
#include "tum_map.hpp"

using namespace rtog;
using namespace rtog_test;

namespace {

using Cells = std::unordered_map<Key, float, KeyHash>;

Cells cellsOf(const OccupancyMap& m) {
  Cells c;
  m.forEachLeaf([&](const Box& b, float v) { forEachCell(b, [&](const Key& k) { c[k] = v; }); });
  return c;
}

const std::array<Key, 6> kFaces = {Key{1, 0, 0}, Key{-1, 0, 0}, Key{0, 1, 0}, Key{0, -1, 0}, Key{0, 0, 1}, Key{0, 0, -1}};
Key plus(const Key& a, const Key& b) { return Key{a.x + b.x, a.y + b.y, a.z + b.z}; }

/// The frontier cell by cell, with each frontier cell's sum of unknown-face normals.
std::map<Key, Eigen::Vector3d> bruteFrontier(const OccupancyMap& m, const FrontierOptions& o) {
  const float occ = m.logOddsModel().occupiedThreshold();
  std::map<Key, Eigen::Vector3d> out;
  const Cells cells = cellsOf(m);
  if (!o.planar) {
    for (const auto& [k, v] : cells) {
      if (v >= occ) continue;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (const Key& f : kFaces)
        if (!cells.count(plus(k, f))) n += Eigen::Vector3d(f.x, f.y, f.z);
      bool any = false;
      for (const Key& f : kFaces) any = any || !cells.count(plus(k, f));
      if (any) out[k] = n;
    }
    return out;
  }
  // Columns of the band: the highest log-odds of the band's known cells (z stored as 0).
  const double res = m.resolution();
  const auto z0 = static_cast<std::int32_t>(std::floor(o.min_z / res)), z1 = static_cast<std::int32_t>(std::floor(o.max_z / res));
  Cells columns;
  for (const auto& [k, v] : cells) {
    if (k.z < z0 || k.z > z1) continue;
    const Key c{k.x, k.y, 0};
    const auto it = columns.find(c);
    if (it == columns.end() || v > it->second) columns[c] = v;
  }
  for (const auto& [k, v] : columns) {
    if (v >= occ) continue;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    bool any = false;
    for (int f = 0; f < 4; ++f)
      if (!columns.count(plus(k, kFaces[f]))) n += Eigen::Vector3d(kFaces[f].x, kFaces[f].y, 0), any = true;
    if (any) out[k] = n;
  }
  return out;
}

/// Connected components (26-connected cells, 8-connected columns): sizes and normalized normals,
/// largest first.
std::vector<std::pair<std::int64_t, Eigen::Vector3d>> bruteRegions(const std::map<Key, Eigen::Vector3d>& cells, bool planar) {
  std::set<Key> left;
  for (const auto& [k, n] : cells) left.insert(k);
  std::vector<std::pair<std::int64_t, Eigen::Vector3d>> out;
  while (!left.empty()) {
    std::deque<Key> todo{*left.begin()};
    left.erase(left.begin());
    std::int64_t size = 0;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    while (!todo.empty()) {
      const Key k = todo.front();
      todo.pop_front();
      ++size, n += cells.at(k);
      for (int dz = planar ? 0 : -1; dz <= (planar ? 0 : 1); ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const auto it = left.find(plus(k, Key{dx, dy, dz}));
            if (it != left.end()) todo.push_back(*it), left.erase(it);
          }
    }
    out.push_back({size, n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero()});
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  return out;
}

void expectFrontiersAsBruteForce(const OccupancyMap& m, const FrontierOptions& o, const std::string& what) {
  const auto want = bruteFrontier(m, o);
  const std::vector<Box> boxes = frontierCells(m, o);
  std::set<Key> got;
  std::int64_t volume = 0;
  for (const Box& b : boxes) {
    const Box flat = o.planar ? Box{Key{b.min.x, b.min.y, 0}, Key{b.max.x, b.max.y, 0}} : b;
    volume += flat.volume();
    forEachCell(flat, [&](const Key& k) { got.insert(k); });
  }
  ASSERT_GT(want.size(), 100u) << what;
  EXPECT_EQ(volume, static_cast<std::int64_t>(got.size())) << what << ": the boxes overlap";
  ASSERT_EQ(got.size(), want.size()) << what;
  EXPECT_TRUE(std::equal(got.begin(), got.end(), want.begin(), [](const Key& a, const auto& b) { return a == b.first; }))
      << what;
  const auto regions = frontierRegions(m, o);
  const auto brute = bruteRegions(want, o.planar);
  ASSERT_EQ(regions.size(), brute.size()) << what;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    ASSERT_EQ(regions[i].cells, brute[i].first) << what << " region " << i;
    // Regions of one size may come in another order: compare normals where sizes are unique.
    const bool unique = (i == 0 || brute[i - 1].first != brute[i].first) &&
                        (i + 1 == brute.size() || brute[i + 1].first != brute[i].first);
    if (unique) {
      EXPECT_LT((regions[i].normal - brute[i].second).norm(), 1e-9) << what << " region " << i;
    }
  }
  std::printf("%s: %zu frontier cells in %zu boxes, %zu regions (largest %lld)\n", what.c_str(), got.size(), boxes.size(),
              regions.size(), static_cast<long long>(regions.empty() ? 0 : regions[0].cells));
}

const std::vector<std::string> kPolicies = {"off", "clamped", "equal"};

CRTreeOccupancyGridMap::Ptr senaMap(const std::string& policy) {
  auto m = mapFromIni("mergePolicy=" + policy);
  for (const auto& f : loadOdometryFrames(dataset(kSena), 120))
    for (const auto& obs : *f.sf) m->insertObservation(*obs, f.pose);
  return m;
}

}  // namespace

TEST(Frontiers, SenaEqualBruteForceIn3DAndInABand) {
  for (const std::string& policy : kPolicies) {
    const auto m = senaMap(policy);
    expectFrontiersAsBruteForce(m->map(), {}, "SENA 3D, " + policy);
    FrontierOptions band;
    band.planar = true;
    band.min_z = -0.5, band.max_z = 1.0;
    expectFrontiersAsBruteForce(m->map(), band, "SENA band, " + policy);
  }
}

TEST(Frontiers, MalagaSimplemapEqualsBruteForce) {
  const auto frames = simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz"));
  for (const std::string& policy : kPolicies) {
    auto again = mapFromIni("mergePolicy=" + policy);
    for (std::size_t i = 0; i < frames.size() / 3; ++i)
      for (const auto& obs : *frames[i].sf) again->insertObservation(*obs, frames[i].pose);
    expectFrontiersAsBruteForce(again->map(), {}, "Malaga 3D, " + policy);
    FrontierOptions band;
    band.planar = true;
    expectFrontiersAsBruteForce(again->map(), band, "Malaga band, " + policy);
  }
}

TEST(Frontiers, TumDepthFramesEqualBruteForce) {
  for (const MergePolicy policy : {MergePolicy::Off, MergePolicy::Clamped, MergePolicy::Equal}) {
    MapParams p;
    p.resolution = 0.05;
    p.merge = policy;
    const OccupancyMap m = test::tumMap(RTOG_TEST_TUM_DIR, p, 3, 4);
    expectFrontiersAsBruteForce(m, {}, std::string("TUM 3D, ") + toString(policy));
    FrontierOptions band;
    band.planar = true;
    band.min_z = 0.2, band.max_z = 0.6;
    expectFrontiersAsBruteForce(m, band, std::string("TUM band, ") + toString(policy));
  }
}

TEST(Frontiers, EmptyMapsAndBadOptions) {
  OccupancyMap m;
  EXPECT_TRUE(frontierCells(m).empty());
  FrontierOptions band;
  band.planar = true;
  EXPECT_TRUE(frontierRegions(m, band).empty());
  band.min_z = 1, band.max_z = 0;
  EXPECT_THROW(frontierRegions(m, band), std::invalid_argument);
  FrontierOptions tiny;
  tiny.min_region_cells = 0;
  EXPECT_THROW(frontierRegions(m, tiny), std::invalid_argument);
}

// O(x): the cell's value at its centre (the prior where unknown), continuous across cell faces
// (also of merged cuboids), its gradient the finite differences of the value.
TEST(OccupancyField, CellValuesAtCentresContinuousWithItsGradient) {
  const auto m = senaMap("equal");
  const OccupancyMap& map = m->map();
  const double res = map.resolution();
  std::vector<Box> leaves;
  map.forEachLeaf([&](const Box& b, float) { leaves.push_back(b); });
  std::mt19937 rng(7);
  std::size_t merged = 0;
  for (int t = 0; t < 2000; ++t) {
    const Box& b = leaves[rng() % leaves.size()];
    merged += b.volume() > 1;
    const Key k = b.min;
    const Eigen::Vector3d centre((k.x + 0.5) * res, (k.y + 0.5) * res, (k.z + 0.5) * res);
    EXPECT_NEAR(occupancyAt(map, centre).log_odds, *map.logOdds(k), 1e-6);
    // Across the cuboid's low x face, the value changes by O(eps), not by a step.
    const double eps = 1e-7;
    const Eigen::Vector3d face(k.x * res, (k.y + 0.3) * res, (k.z + 0.6) * res);
    EXPECT_NEAR(occupancyAt(map, face - Eigen::Vector3d(eps, 0, 0)).log_odds,
                occupancyAt(map, face + Eigen::Vector3d(eps, 0, 0)).log_odds, 1e-4);
    // Inside a cell-centre cube, the gradient is the central difference (the interpolant is
    // linear along each axis there).
    const Eigen::Vector3d p = centre + Eigen::Vector3d(0.31, 0.47, 0.23) * res;
    const FieldValue f = occupancyAt(map, p);
    for (int a = 0; a < 3; ++a) {
      const double h = 1e-3 * res;
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d[a] = h;
      const double fd = (occupancyAt(map, p + d).log_odds - occupancyAt(map, p - d).log_odds) / (2 * h);
      EXPECT_NEAR(f.gradient[a], fd, 1e-6 * std::max(1.0, std::abs(fd)));
    }
    // The band's field: bilinear between the columns, equal at a column's centre.
    const FieldValue g = occupancyAt2D(map, centre, -0.5, 1.0);
    EXPECT_NEAR(g.log_odds, *map.logOdds(k), 1e-6);  // SENA's band holds one layer
    EXPECT_EQ(g.gradient.z(), 0.0);
  }
  EXPECT_GT(merged, 100u);
  // Unknown space and points without a key read the prior.
  const double l0 = map.logOddsModel().prior();
  EXPECT_EQ(occupancyAt(map, Eigen::Vector3d(1e4, 1e4, 1e4)).log_odds, l0);
  EXPECT_EQ(occupancyAt(map, Eigen::Vector3d(1e12, 0, 0)).log_odds, l0);
  EXPECT_EQ(occupancyAt(map, Eigen::Vector3d(std::nan(""), 0, 0)).log_odds, l0);
}
