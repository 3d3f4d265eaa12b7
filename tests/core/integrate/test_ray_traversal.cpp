// Voxel traversal: the walk is a 6-connected path from the start cell to the end cell whose
// cells all touch the segment, and it matches a brute-force slab test in general position; the
// planar batch marks the same cells. (The update batch's queued lane walks: test_update_batch.cpp.)
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <string>

#include "rtog/core/ray_traversal.hpp"
#include "rtog/core/rtree.hpp"  // intersectRay
#include "integrate/planar/fan_skip.hpp"
#include "integrate/planar/planar_batch.hpp"

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

// The cells a planar batch marked free, in layer z.
std::set<Key> markedFree(PlanarBatch& batch, int z) {
  batch.finalize();
  std::set<Key> marked;
  const auto width = static_cast<std::size_t>(batch.width());
  for (std::size_t t = 0; t < batch.tiles().size(); ++t)
    for (int w = 0; w < kLayerWords; ++w)
      for (std::uint64_t bits = batch.tiles()[t].free[static_cast<std::size_t>(w)]; bits; bits &= bits - 1) {
        const int i = w * 64 + __builtin_ctzll(bits);
        const int bx = batch.brickX0() + static_cast<int>(t % width), by = batch.brickY0() + static_cast<int>(t / width);
        marked.insert(Key{bx * kBrickSize + (i & (kBrickSize - 1)), by * kBrickSize + (i >> kBrickBits), z});
      }
  return marked;
}

// The cells in one set and not the other, for a failure message.
std::string difference(const std::set<Key>& got, const std::set<Key>& expected) {
  std::string out;
  const auto list = [&](const std::set<Key>& a, const std::set<Key>& b, const char* label) {
    for (const Key& k : a)
      if (!b.count(k)) out += std::string(label) + " (" + std::to_string(k.x) + ", " + std::to_string(k.y) + ") ";
  };
  list(got, expected, "extra");
  list(expected, got, "missing");
  return out.substr(0, 400);
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
    ASSERT_EQ(markedFree(batch, 3), expected)
        << "trial " << trial << " from (" << a.x() << ", " << a.y() << ") to (" << b.x() << ", " << b.y() << ")";
  }
}

// Leaving out the first k runs of a walk (rows when it steps more along x, else columns; the
// last run stays) marks exactly the walk's cells k or more rows (columns) away from the start.
TEST(RayTraversal, PlanarBatchSkipsLeadingRuns) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> c(-40.0, 40.0);
  std::uniform_int_distribution<int> ci(-40, 40);
  PlanarBatch batch;
  std::int64_t partly_skipped = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    Eigen::Vector3d a(c(rng), c(rng), 0.5), b(c(rng), c(rng), 0.5);
    if (trial % 4 == 1) a = Eigen::Vector3d(ci(rng), ci(rng), 0.5), b = Eigen::Vector3d(ci(rng), ci(rng), 0.5);
    if (trial % 4 == 2) b = a + (b - a) * 6.0;
    const Key ka = floorKey(a), kb = floorKey(b);
    const PlanarSegment seg = planarSegment(a, b, ka, kb);
    const bool rows = seg.nx >= seg.ny;
    const std::int64_t minor_n = rows ? seg.ny : seg.nx;
    const std::int64_t skip = std::uniform_int_distribution<std::int64_t>(0, minor_n + 2)(rng);
    std::set<Key> expected;
    traverseRay(a, b, ka, kb, [&](const Key& k) {
      if (std::abs(rows ? k.y - ka.y : k.x - ka.x) >= std::min(skip, minor_n)) expected.insert(k);
    });
    batch.reset(Key{std::min(ka.x, kb.x), std::min(ka.y, kb.y), 0}, Key{std::max(ka.x, kb.x), std::max(ka.y, kb.y), 0});
    batch.markRayFree(seg, ka, skip);
    const std::set<Key> marked = markedFree(batch, 0);
    ASSERT_TRUE(marked == expected) << "trial " << trial << ", skip " << skip << " from (" << a.x() << ", " << a.y()
                                    << ") to (" << b.x() << ", " << b.y() << "): " << difference(marked, expected);
    partly_skipped += skip > 0 && skip < minor_n;
  }
  EXPECT_GT(partly_skipped, 1000);
}

// A scan's beams marked with fanSkipRuns's skips mark exactly the union of their whole walks:
// sweeps of many angular steps and directions, short, missing and zero-length beams among long
// ones, beams out of sweep order, starts on cell corners, a sweep over a full turn.
TEST(RayTraversal, FanSkipsMarkTheUnionOfTheWholeWalks) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PlanarBatch batch;
  std::int64_t skipped = 0, runs = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Eigen::Vector3d origin(-20.0 + 40.0 * u(rng), -20.0 + 40.0 * u(rng), 2.5);
    if (trial % 5 == 0) origin = Eigen::Vector3d(std::floor(origin.x()), std::floor(origin.y()), 2.5);
    const int count = 20 + static_cast<int>(u(rng) * 400);
    const double full_turn = 6.283185307179586;
    const double step = (trial % 7 == 0 ? full_turn / count : 0.001 + 0.05 * u(rng) * u(rng)) * (trial % 2 ? 1 : -1);
    const double start = full_turn * u(rng), reach = 5.0 + 150.0 * u(rng);
    const Key ka = floorKey(origin);
    std::vector<PlanarBeam> beams(static_cast<std::size_t>(count));
    std::vector<Eigen::Vector3d> ends(beams.size());
    Key lo = ka, hi = ka;
    for (std::size_t i = 0; i < beams.size(); ++i) {
      const double angle = start + step * static_cast<double>(i), r = u(rng);
      // Mostly long beams, some short ones, some of zero length.
      const double range = r < 0.2 ? 12.0 * u(rng) : (r < 0.23 ? 0.0 : reach * (0.5 + 0.5 * u(rng)));
      ends[i] = origin + range * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
      if (r > 0.97 && i > 0) std::swap(ends[i], ends[i - 1]);  // out of sweep order
    }
    for (std::size_t i = 0; i < beams.size(); ++i) {
      PlanarBeam& beam = beams[i];
      beam.end = floorKey(ends[i]);
      beam.traced = u(rng) > 0.03;  // a few missing
      beam.seg = planarSegment(origin, ends[i], ka, beam.end);
      lo = Key{std::min(lo.x, beam.end.x), std::min(lo.y, beam.end.y), 2};
      hi = Key{std::max(hi.x, beam.end.x), std::max(hi.y, beam.end.y), 2};
    }
    fanSkipRuns(beams.data(), beams.size());
    std::set<Key> expected;
    batch.reset(lo, hi);
    for (std::size_t i = 0; i < beams.size(); ++i) {
      const PlanarBeam& beam = beams[i];
      if (!beam.traced) continue;
      traverseRay(origin, ends[i], ka, beam.end, [&](const Key& k) { expected.insert(k); });
      batch.markRayFree(beam.seg, ka, beam.skip_runs);
      skipped += beam.skip_runs;
      runs += beam.seg.nx >= beam.seg.ny ? beam.seg.ny : beam.seg.nx;
    }
    const std::set<Key> marked = markedFree(batch, 2);
    ASSERT_TRUE(marked == expected) << "trial " << trial << ": " << difference(marked, expected);
  }
  // The skips are not idle: a fifth of the runs or more.
  EXPECT_GT(skipped * 5, runs);
}
