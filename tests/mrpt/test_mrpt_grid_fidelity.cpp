// The mrpt_grid preset against MRPT's own COccupancyGridMap2D: a grid section pasted from a
// stock MRPT config, renamed to rtog's map types and nothing else changed, must give the grid's
// cells exactly, on real logs (MRPT's datasets, none of which the preset was tuned on).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "derived_scan.hpp"
#include "grid_fidelity.hpp"
#include "test_helpers.hpp"

using mrpt::maps::CMultiMetricMap;
using mrpt::maps::COccupancyGridMap2D;
using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

bool endPointsOnGrid(const COccupancyGridMap2D& g, const mrpt::obs::CObservation2DRangeScan& scan,
                     const mrpt::poses::CPose3D& robot) {
  const mrpt::poses::CPose3D sensor = robot + scan.sensorPose;
  for (std::size_t i = 0; i < scan.getScanSize(); ++i) {
    if (!scan.getScanRangeValidity(i)) continue;
    const double a = scan.getScanAngle(i), r = scan.getScanRange(i);
    double x, y, z;
    sensor.composePoint(r * std::cos(a), r * std::sin(a), 0, x, y, z);
    if (x < g.getXMin() || x >= g.getXMax() || y < g.getYMin() || y >= g.getYMax()) return false;
  }
  return true;
}

/// Each of COccupancyGridMap2D's seven likelihood methods on rtreeOccupancyGrid against the stock
/// grid built from the same scans, at the frames' poses and displaced ones: the same values.
/// MRPT 2.5.8 gives two of them a constant for every 2D scan (see
/// MapGrid2D.AllSevenMethodsEqualStockGridAndPeakAtTruePose): mean information -inf (its insertion
/// counts no updated cell: log(0)) and consensus OWA 1e-3 (an inverted type check). Both are
/// asserted to be that constant on both maps; OWA is then compared on the scan as a DerivedScan,
/// for which MRPT computes it; and every compared method must vary over the poses.
void expectSameLikelihoods(const COccupancyGridMap2D& stock, const CRTreeOccupancyGridMap& ours,
                           const std::vector<Frame>& frames, const std::string& what) {
  using G = COccupancyGridMap2D;
  for (int method = G::lmMeanInformation; method <= G::lmConsensusOWA; ++method) {
    COccupancyGridMap2D g = stock;
    CRTreeOccupancyGridMap m = ours;
    g.likelihoodOptions.likelihoodMethod = static_cast<G::TLikelihoodMethod>(method);
    m.likelihoodOptions.likelihoodMethod = static_cast<CRTreeOccupancyGridMap::TLikelihoodMethod>(method);
    std::size_t evaluated = 0, differ = 0, off_grid = 0;
    std::set<double> values;
    for (std::size_t i = 0; i < frames.size(); i += 20) {
      const auto plain = frames[i].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
      if (!plain) continue;
      for (const mrpt::poses::CPose3D& d : {mrpt::poses::CPose3D(), mrpt::poses::CPose3D(0.3, 0, 0, 0, 0, 0),
                                            mrpt::poses::CPose3D(0, -0.3, 0, 0.2, 0, 0)}) {
        const mrpt::poses::CPose3D q = frames[i].pose + d;
        if (method == G::lmConsensusOWA) {
          // What MRPT returns for every 2D scan, on both.
          EXPECT_EQ(g.computeObservationLikelihood(*plain, q), 1e-3);
          EXPECT_EQ(m.computeObservationLikelihood(*plain, q), 1e-3);
        }
        // MRPT's lmConsensus reads end points' cells unchecked (off the stock grid its value is
        // undefined) and OWA fails an assertion there: such poses are not compared (counted).
        if ((method == G::lmConsensus || method == G::lmConsensusOWA) && !endPointsOnGrid(stock, *plain, q)) {
          ++off_grid;
          continue;
        }
        const std::optional<DerivedScan> derived =
            method == G::lmConsensusOWA ? std::optional<DerivedScan>(*plain) : std::nullopt;
        const mrpt::obs::CObservation2DRangeScan& scan = derived ? static_cast<const mrpt::obs::CObservation2DRangeScan&>(*derived) : *plain;
        // MI writes the scan into the grid it scores on: each evaluation on a fresh copy.
        const double want = method == G::lmMeanInformation ? COccupancyGridMap2D(g).computeObservationLikelihood(scan, q)
                                                            : g.computeObservationLikelihood(scan, q);
        const double have = m.computeObservationLikelihood(scan, q);
        ++evaluated;
        values.insert(have);
        if (!(want == have)) {  // the same double: MRPT's own code on the same cells
          ++differ;
          ADD_FAILURE() << what << ", method " << method << ", frame " << i << ": " << have << " vs the grid's " << want;
        }
      }
    }
    std::cout << what << ", likelihood method " << method << ": " << evaluated << " evaluations, " << values.size()
              << " distinct values, " << differ << " differ from the stock grid's (" << off_grid
              << " poses with end points off the grid skipped)\n";
    EXPECT_GE(evaluated, 5u);
    if (method == G::lmMeanInformation) {
      EXPECT_EQ(values, std::set<double>{-HUGE_VAL});
    } else {
      EXPECT_GE(2 * values.size(), evaluated) << what << ", method " << method << " hardly varies";
    }
  }
}

void expectSameAsStockGrid(const std::string& config, const std::string& prefix, const std::vector<Frame>& frames,
                           const std::string& what, bool check_likelihoods = false) {
  const std::string ini = readText(kConfigs + config);
  CMultiMetricMap stock = mapsFrom(ini, prefix, "occupancyGrid");
  CMultiMetricMap backed = mapsFrom(ini, prefix, "rtreeGridMap2D");
  CMultiMetricMap rtree = mapsFrom(ini, prefix, "rtreeOccupancyGrid");
  auto g = stock.mapByClass<COccupancyGridMap2D>();
  auto b = backed.mapByClass<rtog::CRTreeBackedGridMap2D>();
  auto r = rtree.mapByClass<CRTreeOccupancyGridMap>();
  ASSERT_TRUE(g && b && r);
  std::size_t scans = 0;
  for (const auto& f : frames) {
    for (const auto& o : *f.sf) {
      if (!IS_CLASS(*o, mrpt::obs::CObservation2DRangeScan)) continue;
      const bool ins = g->insertObservation(*o, f.pose);
      EXPECT_EQ(b->insertObservation(*o, f.pose), ins);
      EXPECT_EQ(r->insertObservation(*o, f.pose), ins);
      scans += ins ? 1 : 0;
    }
  }
  ASSERT_GT(scans, 50u);
  const Figures fb = compareCells(*g, *b);
  const Figures fr = compareRTree(*g, *r);
  std::cout << what << ": " << scans << " scans, grid " << g->getSizeX() << " x " << g->getSizeY() << " = " << fb.cells
            << " cells; rtreeGridMap2D differs in " << fb.differ << " (max " << fb.max_step
            << " int8 steps), rtreeOccupancyGrid in " << fr.differ << " (max " << fr.max_step << ")\n";
  EXPECT_EQ(fb.differ, 0u);
  EXPECT_EQ(fr.differ, 0u);
  EXPECT_EQ(r->map().checkInvariants(), "");
  if (check_likelihoods) expectSameLikelihoods(*g, *r, frames, what);
}

}  // namespace

TEST(MrptGridFidelity, IcpSlamGridmatchConfigOnSena) {
  expectSameAsStockGrid("icp-slam/icp-slam_demo_classic_gridmatch.ini", "MappingApplication", rawlogFrames(dataset(kSena)),
                        "SENA, icp-slam gridmatch section", true);
}

TEST(MrptGridFidelity, RbpfOptimalSamplingConfigOnMalagaSimplemap) {
  expectSameAsStockGrid("rbpf-slam/gridmapping_optimal_sampling.ini", "MappingApplication",
                        simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz")),
                        "Malaga simplemap, rbpf optimal-sampling section");
}

TEST(MrptGridFidelity, IcpSlamGridmatchConfigOnMalagaSimplemap) {
  expectSameAsStockGrid("icp-slam/icp-slam_demo_classic_gridmatch.ini", "MappingApplication",
                        simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz")),
                        "Malaga simplemap, icp-slam gridmatch section");
}

TEST(MrptGridFidelity, PfLocalizationConfigOnLocalizationDemo) {
  expectSameAsStockGrid("pf-localization/localization_demo.ini", "MetricMap",
                        simplemapFrames(dataset("localization_demo.simplemap.gz")),
                        "localization_demo simplemap, pf-localization section", true);
}

// 1-beam scans: MRPT's getScanAngle() divides by zero for them, but the stock grid casts the
// one ray at the first ray's angle (-aperture/2 from right to left); both map types must follow.
TEST(MrptGridFidelity, OneBeamScansOnSena) {
  std::vector<Frame> frames;
  for (const auto& f : rawlogFrames(dataset(kSena))) {
    auto sf = mrpt::obs::CSensoryFrame::Create();
    for (const auto& o : *f.sf) {
      const auto* s = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(o.get());
      if (!s) continue;
      auto one = mrpt::obs::CObservation2DRangeScan::Create(*s);
      const std::size_t mid = s->getScanSize() / 2;
      one->resizeScan(1);
      one->setScanRange(0, s->getScanRange(mid));
      one->setScanRangeValidity(0, s->getScanRangeValidity(mid));
      sf->insert(one);
    }
    frames.push_back({f.pose, sf});
  }
  expectSameAsStockGrid("icp-slam/icp-slam_demo_classic_gridmatch.ini", "MappingApplication", frames,
                        "SENA, each scan cut to its middle beam");
}

// At a resolution that is no power of two the grid's growth meets ties: at 0.08 m an edge grown
// to -25 m is -312.5 cells, which MRPT's round takes to -312 (ties to even), std::round to -313.
// SENA at 0.08 m with default options: the frame as the stock grid's after every frame, and the
// cells the same at the end.
TEST(MrptGridFidelity, GridGrowthRoundsAsTheStockGridAt8cm) {
  auto m = mapFromIni("");
  rtog::CRTreeOccupancyGridMap ours(0.08f, m->insertionOptions);  // MRPT's float 0.08, as the grid's
  COccupancyGridMap2D stock(-10, 10, -10, 10, 0.08f);
  ours.setGridFrame(-10, 10, -10, 10);
  const auto frames = loadOdometryFrames(dataset(kSena));
  std::size_t grew = 0;
  float last = stock.getXMin();
  for (std::size_t i = 0; i < frames.size(); i += 5) {
    for (const auto& obs : *frames[i].sf) ours.insertObservation(*obs, frames[i].pose), stock.insertObservation(*obs, frames[i].pose);
    const auto& f = ours.gridFrame();
    ASSERT_EQ(f.x_min, stock.getXMin()) << "frame " << i;
    ASSERT_EQ(f.x_max, stock.getXMax()) << "frame " << i;
    ASSERT_EQ(f.y_min, stock.getYMin()) << "frame " << i;
    ASSERT_EQ(f.y_max, stock.getYMax()) << "frame " << i;
    grew += stock.getXMin() != last;
    last = stock.getXMin();
  }
  EXPECT_GE(grew, 3u);
  const auto view = ours.gridView();
  ASSERT_EQ(view->getSizeX(), stock.getSizeX());
  ASSERT_EQ(view->getSizeY(), stock.getSizeY());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < stock.getRawMap().size(); ++i) differ += view->getRawMap()[i] != stock.getRawMap()[i];
  EXPECT_EQ(differ, 0u);
}
