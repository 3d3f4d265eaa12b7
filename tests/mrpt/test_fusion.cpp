// CRTreeOccupancyGridMap::fuse on Debian's SENA rawlog: the maps of the first and the second half
// of the loop, built through insertObservation at the odometry poses with settings under which
// no cell can reach a clamp, fuse into the map of the whole loop cell for cell (up to float
// rounding of the sums); the MRPT map's 2D view follows the fused cells.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "map_cells.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;

namespace {

// Every 5th frame of the loop (45): a cell takes at most 45 hits of logit(0.55) = 0.20 and 45 misses
// of logit(0.4) = -0.41, inside the clamps logit(0.99999994) = 16.6 and logit(1e-30) = -69. With
// clamps reached, the halves are clamped apart: the core tests state that case exactly.
constexpr const char* kUnclamped =
    "sensorModelPreset=octomap\nmaxOccupancyUpdateCertainty=0.55\nclampingMin=1e-30\nclampingMax=0.99999994\n";

rtog::CRTreeOccupancyGridMap::Ptr build(const std::vector<PosedFrame>& frames, std::size_t from, std::size_t to) {
  auto m = mapFromIni(kUnclamped);
  for (std::size_t i = from; i < to; ++i)
    for (const auto& obs : *frames[i].sf) m->insertObservation(*obs, frames[i].pose);
  return m;
}

}  // namespace

TEST(Fusion, SenaHalvesWithoutClampingFuseIntoTheWholeLoop) {
  std::vector<PosedFrame> frames;
  {
    const auto all = loadOdometryFrames(dataset(kSena));
    for (std::size_t i = 0; i < all.size(); i += 5) frames.push_back(all[i]);
  }
  ASSERT_EQ(frames.size(), 45u);
  const std::size_t half = frames.size() / 2;
  const auto whole = build(frames, 0, frames.size());
  const auto a = build(frames, 0, half);
  const auto b = build(frames, half, frames.size());
  const std::size_t cells_a = rtog::test::cellsOf(a->map()).size();
  (void)a->gridView();  // a cached view, which the fusion must drop
  const rtog::InsertStats st = a->fuse(*b);
  EXPECT_EQ(st.skipped_out_of_range, 0u);
  EXPECT_EQ(a->map().checkInvariants(), "");
  const auto fused = rtog::test::cellsOf(a->map()), expected = rtog::test::cellsOf(whole->map());
  ASSERT_EQ(fused.size(), expected.size());
  EXPECT_GT(fused.size(), cells_a);
  double worst = 0;
  std::size_t class_differs = 0;
  for (std::size_t i = 0; i < fused.size(); ++i) {
    ASSERT_EQ(fused[i].first, expected[i].first);
    worst = std::max(worst, double(std::fabs(fused[i].second - expected[i].second)));
    class_differs += (fused[i].second >= 0.0f) != (expected[i].second >= 0.0f);
  }
  std::printf("SENA fusion: %zu frames in two halves, %zu cells, largest difference from one build %.3g\n",
              frames.size(), fused.size(), worst);
  EXPECT_LT(worst, 1e-5);
  EXPECT_EQ(class_differs, 0u);
  // The 2D view (what MRPT's apps read) is rebuilt from the fused cells: as a fresh map's of them.
  rtog::CRTreeOccupancyGridMap fresh(a->resolution(), a->insertionOptions);
  fresh.map() = a->map();
  fresh.notifyMapChanged();
  EXPECT_EQ(a->gridView()->getRawMap(), fresh.gridView()->getRawMap());
}
