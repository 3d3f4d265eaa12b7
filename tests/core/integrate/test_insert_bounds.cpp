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
