// Voxel traversal: the walk is a 6-connected path from the start cell to the end cell whose
// cells all touch the segment, and it matches a brute-force slab test in general position; the
// planar batch marks the same cells.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "rtog/core/ray_traversal.hpp"
#include "rtog/core/rtree.hpp"  // intersectRay
#include "rtog/core/update_batch.hpp"

using namespace rtog;

namespace {

Key floorKey(const Eigen::Vector3d& p) {
  return Key{static_cast<std::int32_t>(std::floor(p.x())), static_cast<std::int32_t>(std::floor(p.y())),
             static_cast<std::int32_t>(std::floor(p.z()))};
}

TEST(RayTraversal, MatchesBruteForceOnRandomSegments) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> c(-20.0, 20.0);
  for (int trial = 0; trial < 3000; ++trial) {
    const Eigen::Vector3d a(c(rng), c(rng), c(rng)), b(c(rng), c(rng), c(rng));
    const Key ka = floorKey(a), kb = floorKey(b);
    std::vector<Key> walk;
    const auto n = traverseRay(a, b, ka, kb, [&](const Key& k) { walk.push_back(k); });
    const std::int64_t manhattan =
        std::abs(kb.x - ka.x) + std::abs(kb.y - ka.y) + std::abs(kb.z - ka.z);
    ASSERT_EQ(n, manhattan);
    ASSERT_EQ(static_cast<std::int64_t>(walk.size()), manhattan);
    if (walk.empty()) continue;
    ASSERT_EQ(walk.front(), ka);
    // Each step moves one axis by one; the step after the last visited cell reaches kb.
    walk.push_back(kb);
    for (std::size_t i = 1; i < walk.size(); ++i) {
      const Key& p = walk[i - 1];
      const Key& q = walk[i];
      ASSERT_EQ(std::abs(q.x - p.x) + std::abs(q.y - p.y) + std::abs(q.z - p.z), 1);
    }
    // Brute force: the set of cells whose volume the open segment crosses (slab test on
    // every cell of the bounding box). In general position this is exactly the walk.
    std::set<Key> brute;
    const Eigen::Vector3d d = b - a;
    const Box bb{Key{std::min(ka.x, kb.x), std::min(ka.y, kb.y), std::min(ka.z, kb.z)},
                 Key{std::max(ka.x, kb.x), std::max(ka.y, kb.y), std::max(ka.z, kb.z)}};
    forEachCell(bb, [&](const Key& k) {
      double t0, t1;
      if (intersectRay(a, d, 1.0, Box::cell(k), t0, t1) && t1 - t0 > 1e-9) brute.insert(k);
    });
    const std::set<Key> walked(walk.begin(), walk.end());
    ASSERT_EQ(walked, brute) << "trial " << trial;
  }
}

TEST(RayTraversal, AxisAlignedAndDegenerateSegments) {
  std::vector<Key> walk;
  auto collect = [&](const Key& k) { walk.push_back(k); };
  // Same cell: nothing visited.
  EXPECT_EQ(traverseRay(Eigen::Vector3d(0.2, 0.2, 0.2), Eigen::Vector3d(0.8, 0.9, 0.1), Key{0, 0, 0}, Key{0, 0, 0}, collect), 0);
  EXPECT_TRUE(walk.empty());
  // Along -x across negative keys.
  EXPECT_EQ(traverseRay(Eigen::Vector3d(2.5, 0.5, 0.5), Eigen::Vector3d(-2.5, 0.5, 0.5), Key{2, 0, 0}, Key{-3, 0, 0}, collect), 5);
  ASSERT_EQ(walk.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(walk[static_cast<std::size_t>(i)], (Key{2 - i, 0, 0}));
  // Exactly through a cell corner: still a 6-connected walk that ends at the end cell.
  walk.clear();
  EXPECT_EQ(traverseRay(Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(3.0, 3.0, 3.0), Key{0, 0, 0}, Key{3, 3, 3}, collect), 9);
}

// A segment within one z-layer is walked in exact integer form: the same properties, and the
// same cells as the slab test in general position.
TEST(RayTraversal, PlanarSegmentsMatchBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> c(-40.0, 40.0);
  for (int trial = 0; trial < 3000; ++trial) {
    const Eigen::Vector3d a(c(rng), c(rng), -2.25), b(c(rng), c(rng), -2.75);
    const Key ka = floorKey(a), kb = floorKey(b);
    ASSERT_EQ(ka.z, kb.z);
    std::vector<Key> walk;
    const auto n = traverseRay(a, b, ka, kb, [&](const Key& k) { walk.push_back(k); });
    const std::int64_t manhattan = std::abs(kb.x - ka.x) + std::abs(kb.y - ka.y);
    ASSERT_EQ(n, manhattan);
    ASSERT_EQ(static_cast<std::int64_t>(walk.size()), manhattan);
    if (walk.empty()) continue;
    ASSERT_EQ(walk.front(), ka);
    walk.push_back(kb);
    for (std::size_t i = 1; i < walk.size(); ++i)
      ASSERT_EQ(std::abs(walk[i].x - walk[i - 1].x) + std::abs(walk[i].y - walk[i - 1].y), 1);
    std::set<Key> brute;
    const Eigen::Vector3d d = b - a;
    const Box bb{Key{std::min(ka.x, kb.x), std::min(ka.y, kb.y), ka.z}, Key{std::max(ka.x, kb.x), std::max(ka.y, kb.y), ka.z}};
    forEachCell(bb, [&](const Key& k) {
      double t0, t1;
      if (intersectRay(a, d, 1.0, Box::cell(k), t0, t1) && t1 - t0 > 1e-9) brute.insert(k);
    });
    ASSERT_EQ(std::set<Key>(walk.begin(), walk.end()), brute) << "trial " << trial;
  }
}

// Through cell corners: a walk of cells that touch the segment, in every direction; where
// both boundaries are crossed at once (along +x+y and -x-y from a corner), x goes first.
TEST(RayTraversal, PlanarWalkThroughCornersBreaksTiesTowardsX) {
  for (const int sx : {1, -1})
    for (const int sy : {1, -1}) {
      const Eigen::Vector3d a(3.0, 3.0, 0.5), b(3.0 + 3.0 * sx, 3.0 + 3.0 * sy, 0.5);
      const Key ka = floorKey(a), kb = floorKey(b);
      std::vector<Key> walk;
      const auto n = traverseRay(a, b, ka, kb, [&](const Key& k) { walk.push_back(k); });
      ASSERT_EQ(n, std::int64_t{std::abs(kb.x - ka.x) + std::abs(kb.y - ka.y)});
      walk.push_back(kb);
      for (std::size_t i = 0; i < walk.size(); ++i) {
        double t0, t1;
        EXPECT_TRUE(intersectRay(a, b - a, 1.0, Box::cell(walk[i]), t0, t1)) << sx << " " << sy << " cell " << i;
        if (i > 0) {
          EXPECT_EQ(std::abs(walk[i].x - walk[i - 1].x) + std::abs(walk[i].y - walk[i - 1].y), 1);
        }
      }
      if (sx == sy) {
        for (std::size_t i = 1; i < walk.size(); ++i)
          EXPECT_EQ(walk[i].x != walk[i - 1].x, i % 2 == 1) << sx << " " << sy << " step " << i;
      }
    }
}

// Long planar segments near the ends of the key range: the products of the exact form stay in
// range (UBSan would see an overflow), and the walk still ends at the end cell.
TEST(RayTraversal, LongPlanarSegmentsAcrossTheKeyRange) {
  const double edge = kKeyMax - 0.5;
  const Eigen::Vector3d a(-edge, -edge + 10.25, 7.5), b(edge, edge - 3.75, 7.5);
  const Key ka = floorKey(a), kb = floorKey(b);
  Key last = ka;
  std::int64_t visited = 0;
  bool connected = true;
  const auto n = traverseRay(a, b, ka, kb, [&](const Key& k) {
    if (visited++ > 0) connected = connected && std::abs(k.x - last.x) + std::abs(k.y - last.y) == 1;
    last = k;
  });
  EXPECT_EQ(n, std::int64_t{kb.x} - ka.x + kb.y - ka.y);
  EXPECT_EQ(visited, n);
  EXPECT_TRUE(connected);
  EXPECT_EQ(std::abs(kb.x - last.x) + std::abs(kb.y - last.y), 1);
}

}  // namespace

// The planar batch (a dense grid of tiles) marks exactly walkRay's cells: random segments,
// segments from cell corners, exact diagonals and axis-parallel ones, across tile borders and
// negative keys.
TEST(RayTraversal, PlanarBatchWalkMarksWalkRaysCells) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> c(-70.0, 70.0);
  std::uniform_int_distribution<int> ci(-70, 70), kind(0, 5);
  PlanarBatch batch;
  for (int trial = 0; trial < 4000; ++trial) {
    Eigen::Vector3d a(c(rng), c(rng), 3.5), b(c(rng), c(rng), 3.5);
    switch (kind(rng)) {
      case 1:  // cell corners: every boundary crossing a tie
        a = Eigen::Vector3d(ci(rng), ci(rng), 3.5), b = Eigen::Vector3d(ci(rng), ci(rng), 3.5);
        break;
      case 2: {  // exact diagonal
        const double s = c(rng);
        b = a + Eigen::Vector3d(s, trial % 2 ? s : -s, 0.0);
        break;
      }
      case 3:  // axis-parallel
        b[trial % 2] = a[trial % 2];
        break;
      case 4:  // long: runs across many tiles
        b = a + Eigen::Vector3d(c(rng), c(rng), 0.0) * 15.0;
        break;
      default: break;
    }
    const Key ka = floorKey(a), kb = floorKey(b);
    std::set<Key> expected;
    traverseRay(a, b, ka, kb, [&](const Key& k) { expected.insert(k); });
    // The batch spans the segment's cells, as the scan's bounding box does in insertPointCloud.
    batch.reset(Key{std::min(ka.x, kb.x), std::min(ka.y, kb.y), 3}, Key{std::max(ka.x, kb.x), std::max(ka.y, kb.y), 3});
    batch.markRayFree(a, b, ka, kb);
    std::set<Key> marked;
    for (std::size_t t = 0; t < batch.tiles().size(); ++t)
      for (int w = 0; w < kLayerWords; ++w)
        for (std::uint64_t bits = batch.tiles()[t].free[static_cast<std::size_t>(w)]; bits; bits &= bits - 1) {
          const int i = w * 64 + __builtin_ctzll(bits);
          const int bx = batch.brickX0() + static_cast<int>(t % static_cast<std::size_t>(batch.width()));
          const int by = batch.brickY0() + static_cast<int>(t / static_cast<std::size_t>(batch.width()));
          marked.insert(Key{bx * kBrickSize + (i & (kBrickSize - 1)), by * kBrickSize + (i >> kBrickBits), 3});
        }
    ASSERT_EQ(marked, expected) << "trial " << trial << " from (" << a.x() << ", " << a.y() << ") to (" << b.x()
                                << ", " << b.y() << ")";
  }
}
