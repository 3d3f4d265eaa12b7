// Copies of CRTreeOccupancyGridMap as a particle filter makes them: the stock rbpf-slam grid
// section pasted as rtreeOccupancyGrid, copied between scans, each copy taking scans at its own
// poses. Every copy must score scans exactly as a COccupancyGridMap2D that took the same scans
// (the 2D view's copy-on-write tiles follow each copy's own scans), an empty map must be scored as
// the stock grid scores its empty grid, and copies must score on several threads at once while
// another copy inserts (TSan runs the MapConcurrency cases).
#include <gtest/gtest.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CRawlog.h>

#include <atomic>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using mrpt::maps::COccupancyGridMap2D;
using mrpt::obs::CObservation2DRangeScan;
using mrpt::poses::CPose3D;
using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

/// The stock rbpf-slam config's grid, as shipped and renamed to rtreeOccupancyGrid.
struct Pair {
  COccupancyGridMap2D::Ptr grid;
  CRTreeOccupancyGridMap::Ptr rtog;
};

/// The stock rbpf-slam config's maps: its grid as shipped, and renamed to `type`.
std::pair<COccupancyGridMap2D::Ptr, mrpt::maps::CMetricMap::Ptr> stockAnd(const std::string& type);

Pair stockPair() {
  auto [grid, ours] = stockAnd("rtreeOccupancyGrid");
  return {grid, std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(ours)};
}

std::pair<COccupancyGridMap2D::Ptr, mrpt::maps::CMetricMap::Ptr> stockAnd(const std::string& type) {
  std::ifstream f("/usr/share/mrpt/config_files/rbpf-slam/gridmapping_optimal_sampling.ini");
  std::stringstream ss;
  ss << f.rdbuf();
  std::string text = ss.str(), renamed = text;
  for (auto [from, to] : {std::pair<std::string, std::string>{"occupancyGrid_count", type + "_count"},
                          {"_occupancyGrid_00_", "_" + type + "_00_"}})
    for (std::size_t p = 0; (p = renamed.find(from, p)) != std::string::npos; p += to.size()) renamed.replace(p, from.size(), to);
  return {std::dynamic_pointer_cast<COccupancyGridMap2D>(multiMapFromIni(text).maps.at(0)),
          multiMapFromIni(renamed).maps.at(0)};
}

const std::vector<PosedFrame>& senaFrames() {
  static const std::vector<PosedFrame> frames = loadOdometryFrames(dataset(kSena), 120);
  return frames;
}

CObservation2DRangeScan::Ptr scanOf(std::size_t i) {
  return senaFrames()[i].sf->getObservationByClass<CObservation2DRangeScan>();
}

/// Scores of scan `s` at poses about `at` (seed fixed), on `m`.
std::vector<double> scores(const mrpt::maps::CMetricMap& m, const CObservation2DRangeScan& s, const CPose3D& at,
                           unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-0.5, 0.5), a(-0.3, 0.3);
  std::vector<double> out;
  for (int i = 0; i < 40; ++i)
    out.push_back(m.computeObservationLikelihood(s, CPose3D(at.x() + d(rng), at.y() + d(rng), 0, at.yaw() + a(rng), 0, 0)));
  return out;
}

TEST(MapCopies, AnEmptyMapIsScoredAsTheStockGridScoresItsEmptyGrid) {
  const Pair p = stockPair();
  const auto s = scanOf(3);
  ASSERT_TRUE(p.grid->canComputeObservationLikelihood(*s));
  EXPECT_TRUE(p.rtog->canComputeObservationLikelihood(*s));  // was false: the first weighing skipped
  EXPECT_EQ(scores(*p.rtog, *s, CPose3D(), 1), scores(*p.grid, *s, CPose3D(), 1));
}

// Each copy takes scans at poses of its own, as particles do: its scores stay the stock grid's
// that took the same scans, bit for bit, and the map it was copied from is not touched.
void copiesScoreAsStockGrids(const std::vector<PosedFrame>& frames) {
  ASSERT_GE(frames.size(), 30u);
  // The first third into both, then each copy its own way to the end; scored every few scans.
  const std::size_t first = std::min<std::size_t>(20, frames.size() / 3), last = frames.size() - 1;
  const auto scanOf = [&](std::size_t i) { return frames[i].sf->getObservationByClass<CObservation2DRangeScan>(); };
  Pair a = stockPair();
  for (std::size_t i = 0; i < first; ++i) {
    a.grid->insertObservation(*scanOf(i), frames[i].pose);
    a.rtog->insertObservation(*scanOf(i), frames[i].pose);
  }
  const CPose3D probe = frames[first].pose;
  ASSERT_EQ(scores(*a.rtog, *scanOf(first), probe, 2), scores(*a.grid, *scanOf(first), probe, 2));
  const std::vector<double> before = scores(*a.rtog, *scanOf(first), probe, 3);
  // Two copies of each, every one going on with poses nudged its own way.
  std::vector<Pair> copies;
  for (int c = 0; c < 2; ++c)
    copies.push_back({std::make_shared<COccupancyGridMap2D>(*a.grid), std::make_shared<CRTreeOccupancyGridMap>(*a.rtog)});
  for (std::size_t i = first; i < last; ++i)
    for (int c = 0; c < 2; ++c) {
      const CPose3D pose = frames[i].pose + CPose3D(0.02 * (c + 1), -0.01 * c, 0, 0.01 * c, 0, 0);
      copies[c].grid->insertObservation(*scanOf(i), pose);
      copies[c].rtog->insertObservation(*scanOf(i), pose);
      if (i % 5 == 4 || i + 1 == last) {
        const CPose3D at = frames[i + 1].pose;
        ASSERT_EQ(scores(*copies[c].rtog, *scanOf(i + 1), at, 4), scores(*copies[c].grid, *scanOf(i + 1), at, 4))
            << "copy " << c << " after scan " << i;
        // A copy of a copy, as resampling makes them, scores as its source.
        const CRTreeOccupancyGridMap again(*copies[c].rtog);
        ASSERT_EQ(scores(again, *scanOf(i + 1), at, 5), scores(*copies[c].rtog, *scanOf(i + 1), at, 5));
      }
    }
  EXPECT_EQ(scores(*a.rtog, *scanOf(first), probe, 3), before) << "scans into copies changed the original";
  EXPECT_NE(scores(*copies[0].rtog, *scanOf(last), frames[last].pose, 6),
            scores(*copies[1].rtog, *scanOf(last), frames[last].pose, 6));
}

TEST(MapCopies, CopiesTakingScansAtTheirOwnPosesScoreAsStockGridsThatTookThem) { copiesScoreAsStockGrids(senaFrames()); }

// The same on a log of another robot and building (MRPT's localization demo), not used in tuning.
TEST(MapCopies, CopiesScoreAsStockGridsOnTheLocalizationDemoLog) {
  copiesScoreAsStockGrids(loadOdometryFrames(dataset("localization_demo.rawlog"), 120));
}

// An rtreeGridMap2D copy (its R-tree map's bricks shared, its grid and kept likelihood-field terms
// copied) scores as its source; after a scan of its own, as a map that took every scan.
TEST(MapCopies, ABackedGridCopyScoresAsItsSource) {
  const std::string ini = "[MappingApplication]\nrtreeGridMap2D_count=1\n"
                          "[MappingApplication_rtreeGridMap2D_00_creationOpts]\nresolution=0.07\n"
                          "[MappingApplication_rtreeGridMap2D_00_likelihoodOpts]\nlikelihoodMethod=4\nenableLikelihoodCache=1\n";
  const auto make = [&] { return std::dynamic_pointer_cast<rtog::CRTreeBackedGridMap2D>(multiMapFromIni(ini).maps.at(0)); };
  auto g = make(), fresh = make();
  ASSERT_TRUE(g && fresh);
  for (std::size_t i = 0; i < 20; ++i) g->insertObservation(*scanOf(i), senaFrames()[i].pose);
  const CPose3D at = senaFrames()[20].pose;
  const std::vector<double> want = scores(*g, *scanOf(20), at, 8);  // fills the source's kept values
  const rtog::CRTreeBackedGridMap2D copy(*g);
  EXPECT_EQ(scores(copy, *scanOf(20), at, 8), want);
  EXPECT_EQ(scores(*g, *scanOf(20), at, 8), want);
  // A copy of the copy takes one more scan: it scores as a map that took all the scans.
  rtog::CRTreeBackedGridMap2D moved(copy);
  moved.insertObservation(*scanOf(21), senaFrames()[21].pose);
  for (std::size_t i = 0; i < 20; ++i) fresh->insertObservation(*scanOf(i), senaFrames()[i].pose);
  fresh->insertObservation(*scanOf(21), senaFrames()[21].pose);
  EXPECT_EQ(scores(moved, *scanOf(22), senaFrames()[22].pose, 9), scores(*fresh, *scanOf(22), senaFrames()[22].pose, 9));
  EXPECT_EQ(scores(*g, *scanOf(20), at, 8), want);
}

// rtreeGridMap2D drops only the kept likelihood-field terms a scan's cells can reach (the stock
// grid drops them all) and scores on the grid's own kept terms: scored between scans, as a
// particle filter does, it gives the stock grid's values at every step.
TEST(MapCopies, ABackedGridScoredBetweenScansScoresAsTheStockGrid) {
  auto [grid, ours] = stockAnd("rtreeGridMap2D");
  ASSERT_TRUE(grid && ours);
  for (std::size_t i = 0; i + 1 < 80; ++i) {
    const CPose3D next = senaFrames()[i + 1].pose;
    ASSERT_EQ(scores(*ours, *scanOf(i + 1), next, 10 + unsigned(i)), scores(*grid, *scanOf(i + 1), next, 10 + unsigned(i)))
        << "before scan " << i;
    grid->insertObservation(*scanOf(i), senaFrames()[i].pose);
    ours->insertObservation(*scanOf(i), senaFrames()[i].pose);
  }
}

// Copies sharing tiles and bricks score on two threads while a third copy takes scans.
TEST(MapConcurrency, CopiesSharingTheirViewScoreOnThreadsWhileAnotherCopyInserts) {
  Pair a = stockPair();
  for (std::size_t i = 0; i < 30; ++i) a.rtog->insertObservation(*scanOf(i), senaFrames()[i].pose);
  const CRTreeOccupancyGridMap c1(*a.rtog), c2(*a.rtog);
  const CPose3D at = senaFrames()[30].pose;
  const auto s = scanOf(30);
  const std::vector<double> want = scores(*a.rtog, *s, at, 7);
  std::atomic<int> wrong{0};
  std::thread t1([&] {
    for (int k = 0; k < 5; ++k) wrong += scores(c1, *s, at, 7) != want;
  });
  std::thread t2([&] {
    for (int k = 0; k < 5; ++k) wrong += scores(c2, *s, at, 7) != want;
  });
  CRTreeOccupancyGridMap c3(*a.rtog);
  for (std::size_t i = 30; i < 45; ++i) c3.insertObservation(*scanOf(i), senaFrames()[i].pose);
  t1.join();
  t2.join();
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
