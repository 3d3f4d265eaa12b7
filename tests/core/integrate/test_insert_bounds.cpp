// The cost of one beam is bounded: garbage ranges (100 km readings) are skipped and counted,
// not traced through millions of cells (before: 64 such beams, 82 M leaves, 107 s).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <sstream>
#include <vector>

#include "rtog/core/occupancy_map.hpp"

namespace {

std::string bytesOf(const rtog::OccupancyMap& m) {
  std::ostringstream os;
  m.write(os);
  return os.str();
}

/// A fan of `n` beams of `length` metres from `origin`, level (planar) or climbing (3D).
std::vector<Eigen::Vector3f> fan(const Eigen::Vector3d& origin, int n, double length, bool planar) {
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    pts.emplace_back(static_cast<float>(origin.x() + length * std::cos(a)),
                     static_cast<float>(origin.y() + length * std::sin(a)),
                     static_cast<float>(origin.z() + (planar ? 0.0 : 0.01 * length)));
  }
  return pts;
}

TEST(InsertBounds, HundredKilometreBeamsAreSkippedAndCounted) {
  for (const bool planar : {true, false}) {
    SCOPED_TRACE(planar ? "planar scan" : "3D scan");
    rtog::MapParams p;
    p.resolution = 0.1;  // 100 km are 10^6 cells, within the key range (+-104 km)
    rtog::OccupancyMap map(p);
    const Eigen::Vector3d origin(0.05, 0.05, 0.05);
    map.insertPointCloud(origin, fan(origin, 360, 8.0, planar));  // some real content first
    const std::string before = bytesOf(map);
    const auto t0 = std::chrono::steady_clock::now();
    const rtog::InsertStats st = map.insertPointCloud(origin, fan(origin, 64, 100e3, planar));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(st.skipped_too_long, 64u);
    EXPECT_EQ(st.raysTotal(), 64u);
    EXPECT_EQ(st.cells_free + st.cells_occupied, 0u);
    EXPECT_TRUE(bytesOf(map) == before) << "the map changed";
    EXPECT_LT(s, 1.0);
  }
}

TEST(InsertBounds, TheBoundIsInCellsAndCanBeMovedOrLifted) {
  rtog::MapParams p;
  p.resolution = 0.1;
  const Eigen::Vector3d origin(0.05, 0.05, 0.05);
  const double longest = rtog::InsertParams{}.max_ray_cells * p.resolution;  // 6553.6 m
  const std::vector<Eigen::Vector3f> within{Eigen::Vector3f(float(longest - 1.0), 0.05f, 0.05f)},
      beyond{Eigen::Vector3f(float(longest + 1.0), 0.05f, 0.05f)};
  rtog::OccupancyMap map(p);
  EXPECT_EQ(map.insertPointCloud(origin, within).rays_hit, 1u);
  EXPECT_EQ(map.insertPointCloud(origin, beyond).skipped_too_long, 1u);
  // A max_range cut applies first: the cut beam is within the bound.
  rtog::InsertParams cut;
  cut.max_range = 50.0;
  EXPECT_EQ(map.insertPointCloud(origin, beyond, cut).rays_truncated, 1u);
  // A smaller bound, and none (the caller's call).
  rtog::InsertParams small, none;
  small.max_ray_cells = 100;
  none.max_ray_cells = 0;
  EXPECT_EQ(map.insertPointCloud(origin, {Eigen::Vector3f(20.0f, 0.05f, 0.05f)}, small).skipped_too_long, 1u);
  EXPECT_EQ(map.insertPointCloud(origin, beyond, none).rays_hit, 1u);
  EXPECT_EQ(map.checkInvariants(), "");
}

}  // namespace

namespace {

// One scan's memory is bounded (InsertParams::max_scan_cells): 361 beams of 3,276 m, each within
// max_ray_cells, touch 1.85 million bricks (before: 3.2 GB and 23 million leaves for one scan). The
// scan is skipped whole, every beam counted, the map unchanged.
TEST(InsertBounds, AScanOverTheCellBudgetIsSkippedWholeAndCounted) {
  for (const bool planar : {true, false}) {
    SCOPED_TRACE(planar ? "planar scan" : "3D scan");
    rtog::OccupancyMap map(rtog::MapParams{});  // 5 cm
    const Eigen::Vector3d origin(0.02, 0.02, 0.02);
    map.insertPointCloud(origin, fan(origin, 360, 8.0, planar));
    const std::string before = bytesOf(map);
    const rtog::InsertStats st = map.insertPointCloud(origin, fan(origin, 361, 3276.0, planar));
    EXPECT_EQ(st.skipped_over_budget, 361u);
    EXPECT_EQ(st.raysTotal(), 361u);
    EXPECT_EQ(st.cells_free + st.cells_occupied + st.leaves_created, 0u);
    EXPECT_TRUE(bytesOf(map) == before) << "the map changed";
    EXPECT_EQ(map.checkInvariants(), "");
  }
}

// The decision is the scan's, not the threads': a scan of 20,000 beams (four threads) over a
// smaller budget is skipped at any thread count, and under a larger one inserted, the same map
// as with no budget at all.
TEST(InsertBounds, TheCellBudgetDecidesAlikeForAnyThreadCountAndLeavesScansUnderItAlone) {
  const Eigen::Vector3d origin(0.02, 0.02, 0.02);
  const std::vector<Eigen::Vector3f> scan = fan(origin, 20000, 60.0, false);
  std::string unbounded;
  {
    rtog::OccupancyMap map(rtog::MapParams{});
    rtog::InsertParams none;
    none.max_scan_cells = 0;
    EXPECT_EQ(map.insertPointCloud(origin, scan, none).skipped_over_budget, 0u);
    unbounded = bytesOf(map);
  }
  for (const int threads : {1, 2, 4}) {
    SCOPED_TRACE(threads);
    rtog::InsertParams small, large;
    small.threads = large.threads = threads;
    small.max_scan_cells = std::uint64_t{1} << 22;  // 1,024 bricks
    large.max_scan_cells = std::uint64_t{1} << 27;  // 32,768 bricks
    rtog::OccupancyMap map(rtog::MapParams{});
    EXPECT_EQ(map.insertPointCloud(origin, scan, small).skipped_over_budget, scan.size());
    EXPECT_EQ(map.leafCount(), 0u);
    EXPECT_EQ(map.insertPointCloud(origin, scan, large).skipped_over_budget, 0u);
    EXPECT_TRUE(bytesOf(map) == unbounded) << "not the map inserted without a budget";
  }
  // The default budget leaves the scan alone too.
  rtog::OccupancyMap map(rtog::MapParams{});
  EXPECT_EQ(map.insertPointCloud(origin, scan).skipped_over_budget, 0u);
  EXPECT_TRUE(bytesOf(map) == unbounded);
}

}  // namespace

namespace {

// A scan inserted with pose uncertainty (insertBlurred: one trace per pose) is held to the same
// budget, pose by pose: over it, skipped whole and its beams counted once; under it, the map is
// the one inserted without a budget.
TEST(InsertBounds, APoseBlurredScanOverTheCellBudgetIsSkippedWholeAndCounted) {
  const Eigen::Vector3d origin(0.02, 0.02, 0.02);
  const std::vector<Eigen::Vector3f> scan = fan(origin, 20000, 60.0, false);
  const auto poses = [&](const Eigen::Vector3d& o) {
    rtog::WeightedScan a, b;
    a.weight = b.weight = 0.5;
    a.origin = o, b.origin = o + Eigen::Vector3d(0.1, 0.0, 0.0);
    a.points = b.points = scan.data();
    a.count = b.count = scan.size();
    return std::vector<rtog::WeightedScan>{a, b};
  };
  std::string unbounded;
  {
    rtog::OccupancyMap map(rtog::MapParams{});
    rtog::InsertParams none;
    none.max_scan_cells = 0;
    EXPECT_EQ(map.insertBlurred(poses(origin), none).skipped_over_budget, 0u);
    unbounded = bytesOf(map);
  }
  for (const int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    rtog::InsertParams small, large;
    small.threads = large.threads = threads;
    small.max_scan_cells = std::uint64_t{1} << 22;
    large.max_scan_cells = std::uint64_t{1} << 27;
    rtog::OccupancyMap map(rtog::MapParams{});
    const rtog::InsertStats st = map.insertBlurred(poses(origin), small);
    EXPECT_EQ(st.skipped_over_budget, scan.size());
    EXPECT_EQ(st.raysTotal(), scan.size());
    EXPECT_EQ(map.leafCount(), 0u);
    EXPECT_EQ(map.insertBlurred(poses(origin), large).skipped_over_budget, 0u);
    EXPECT_TRUE(bytesOf(map) == unbounded) << "not the map inserted without a budget";
  }
}

}  // namespace
