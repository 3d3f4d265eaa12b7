// rtreeGridMap2D (CRTreeBackedGridMap2D) with lmConsensus: end points beyond the grid.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose2D.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "registration_helpers.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;
using mrpt::maps::COccupancyGridMap2D;
using mrpt::obs::CObservation2DRangeScan;

namespace {

const std::vector<PosedFrame>& senaFrames() {
  static const std::vector<PosedFrame> f = loadOdometryFrames(dataset(kSena), 30);
  return f;
}

// The first 30 SENA frames in a backed grid of 0.05 m, scored by consensus.
rtog::CRTreeBackedGridMap2D& senaBacked() {
  static rtog::CRTreeBackedGridMap2D g = [] {
    rtog::CRTreeBackedGridMap2D m(0.05);
    for (const auto& f : senaFrames()) f.sf->insertObservationsInto(m, f.pose);
    m.likelihoodOptions.likelihoodMethod = COccupancyGridMap2D::lmConsensus;
    return m;
  }();
  return g;
}

// Whether every end point of `scan` at `pose` lies on g's cells (where MRPT's consensus is defined).
bool endPointsOnGrid(const COccupancyGridMap2D& g, const CObservation2DRangeScan& scan, const mrpt::poses::CPose2D& pose) {
  const auto* pts = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>();
  for (std::size_t i = 0; i < pts->size(); ++i) {
    mrpt::math::TPoint2D l, w;
    pts->getPoint(i, l);
    pose.composePoint(l, w);
    if (!(w.x >= g.getXMin() && w.x < g.getXMax() && w.y >= g.getYMin() && w.y < g.getYMax())) return false;
  }
  return true;
}

/// Scores `scan`s of `frames` (beams cut at `reach` [m]) at poses around their own on `map` and
/// on `stock`, where every end point lies on `stock`'s cells (MRPT's consensus is defined there):
/// the same double each time. Returns how many poses were compared.
int compareWithStock(const mrpt::maps::CMetricMap& map, const COccupancyGridMap2D& stock,
                     const std::vector<PosedFrame>& frames, float reach) {
  int compared = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto full = frames[i].sf->getObservationByClass<CObservation2DRangeScan>();
    if (!full) continue;
    auto scan = std::make_shared<CObservation2DRangeScan>(*full);
    for (std::size_t k = 0; k < scan->getScanSize(); ++k)
      if (scan->getScanRange(k) > reach) scan->setScanRangeValidity(k, false);
    for (double dx : {-0.3, 0.0, 0.2})
      for (double dyaw : {-0.1, 0.0, 0.15}) {
        const mrpt::poses::CPose3D q = frames[i].pose + mrpt::poses::CPose3D(dx, 0.1, 0, dyaw, 0, 0);
        if (!endPointsOnGrid(stock, *scan, mrpt::poses::CPose2D(q))) continue;
        EXPECT_EQ(map.computeObservationLikelihood(*scan, q), stock.computeObservationLikelihood(*scan, q))
            << "frame " << i << " at " << q.asString();
        ++compared;
      }
  }
  return compared;
}

}  // namespace

// Issue #37: SENA frame 15 at its own pose reaches beyond the backed grid, whose consensus was
// MRPT's, which reads the cells of end points without a bounds check (SIGSEGV, as a stock grid
// does). Run in a child process, so that a crash fails this test instead of ending the binary.
// Its value: the stock grid's once that grid is grown (unknown cells) to hold every end point.
TEST(BackedGridConsensus, EndPointsBeyondTheGridDoNotCrash) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto scan = senaFrames()[15].sf->getObservationByClass<CObservation2DRangeScan>();
  ASSERT_TRUE(scan);
  const mrpt::poses::CPose3D pose = senaFrames()[15].pose;
  const mrpt::poses::CPose2D pose2(pose);
  EXPECT_EXIT(
      {
        const auto& g = senaBacked();
        if (endPointsOnGrid(g, *scan, pose2)) {
          std::fprintf(stderr, "the scan lies on the grid: not the case this test is for\n");
          std::exit(2);
        }
        const double l = g.computeObservationLikelihood(*scan, pose);
        // The stock grid grown to hold the scan's reach (its new cells unknown).
        COccupancyGridMap2D stock = g;
        const double r = scan->maxRange + 1.0;
        stock.resizeGrid(float(pose2.x() - r), float(pose2.x() + r), float(pose2.y() - r), float(pose2.y() + r), 0.5f,
                         false);
        const double s = stock.computeObservationLikelihood(*scan, pose);
        if (!(std::isfinite(l) && l == s)) {
          std::fprintf(stderr, "backed %.17g, grown stock grid %.17g\n", l, s);
          std::exit(3);
        }
        std::exit(0);
      },
      ::testing::ExitedWithCode(0), "");
}

// Wherever the stock grid's consensus is defined (every end point on its cells), the backed grid
// scores the same double: SENA scans (their beams up to 4 m, so that they lie within the grid) at
// poses around their own.
TEST(BackedGridConsensus, EqualsTheStockGridWhereItIsDefined) {
  const auto& g = senaBacked();
  const int compared = compareWithStock(g, COccupancyGridMap2D(g), senaFrames(), 4.0f);
  std::printf("SENA: compared at %d poses\n", compared);
  EXPECT_GE(compared, 20);
}

// The same on a log the consensus rule was not written against: the Malaga CS building's
// simplemap (corrected poses), its first 40 frames. Also for the R-tree map's 2D view, whose
// consensus goes through the same function: against a stock grid that inserted the scans itself.
TEST(BackedGridConsensus, EqualsTheStockGridOnTheMalagaBuilding) {
  auto frames = simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz"));
  frames.resize(std::min<std::size_t>(frames.size(), 40));
  rtog::CRTreeBackedGridMap2D backed(0.05);
  COccupancyGridMap2D stock(-10, 10, -10, 10, 0.05);
  auto native = mapFromSections("resolution=0.05", "");
  for (const auto& f : frames) {
    f.sf->insertObservationsInto(backed, f.pose);
    f.sf->insertObservationsInto(stock, f.pose);
    f.sf->insertObservationsInto(*native, f.pose);
  }
  backed.likelihoodOptions.likelihoodMethod = COccupancyGridMap2D::lmConsensus;
  stock.likelihoodOptions.likelihoodMethod = COccupancyGridMap2D::lmConsensus;
  native->likelihoodOptions.likelihoodMethod = rtog::CRTreeOccupancyGridMap::lmConsensus;
  int compared = compareWithStock(backed, COccupancyGridMap2D(backed), frames, 4.0f);
  std::printf("Malaga, backed grid: compared at %d poses\n", compared);
  EXPECT_GE(compared, 20);
  compared = compareWithStock(*native, stock, frames, 4.0f);
  std::printf("Malaga, the R-tree map's 2D view: compared at %d poses\n", compared);
  EXPECT_GE(compared, 20);
}
