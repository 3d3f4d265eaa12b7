// The estimator's graded models in the mrpt_grid preset (src/grid_graded.hpp), against MRPT's own
// COccupancyGridMap2D on SENA: with sigma -> 0 and a certain pose they are the grid, cell for
// cell; otherwise their changes land on the grid's int8 lattice, touch only the cells near the
// readings (range noise) and mix the poses' changes (pose blur).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <thread>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "grid_fidelity.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using mrpt::maps::COccupancyGridMap2D;
using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

const char* kSection = "icp-slam/icp-slam_demo_classic_gridmatch.ini";

struct Pair {
  mrpt::maps::CMultiMetricMap stock, ours;
  COccupancyGridMap2D* g = nullptr;
  CRTreeOccupancyGridMap* r = nullptr;
};

/// A stock config's grid section pasted twice: the grid, and rtreeOccupancyGrid with `extra` lines
/// added to its _insertOpts.
std::unique_ptr<Pair> pasted(const std::string& extra = "", const std::string& config = kSection,
                             const std::string& prefix = "MappingApplication") {
  const std::string ini = readText(kConfigs + config);
  auto p = std::make_unique<Pair>();
  p->stock = mapsFrom(ini, prefix, "occupancyGrid");
  p->ours = mapsFrom(ini, prefix, "rtreeOccupancyGrid", extra);
  p->g = p->stock.mapByClass<COccupancyGridMap2D>().get();
  p->r = p->ours.mapByClass<CRTreeOccupancyGridMap>().get();
  if (!p->g || !p->r) throw std::runtime_error("the pasted sections made no maps");
  return p;
}

const std::vector<Frame>& sena() {
  static const std::vector<Frame> frames = rawlogFrames(dataset(kSena));
  return frames;
}

mrpt::obs::CObservation2DRangeScan::Ptr scanOf(const Frame& f) {
  return f.sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
}

/// The map's cells of the grid's layer by lattice key (x, y), as int8 grid cells; every value
/// must be one (on the lattice, within +-127).
std::map<std::pair<int, int>, int> cellsOf(const CRTreeOccupancyGridMap& m) {
  std::map<std::pair<int, int>, int> out;
  std::size_t off_lattice = 0;
  m.map().forEachLeaf([&](const rtog::Box& b, float v) {
    const float c = -v * 16.0f;
    if (c != std::round(c) || std::abs(c) > 127.0f) ++off_lattice;
    rtog::forEachCell(b, [&](const rtog::Key& k) {
      EXPECT_EQ(k.z, m.gridFrame().layer);
      out[{k.x, k.y}] = static_cast<int>(std::lround(c));
    });
  });
  EXPECT_EQ(off_lattice, 0u) << "leaves whose value is no int8 cell";
  return out;
}

int stockCell(const COccupancyGridMap2D& g, int kx, int ky) {
  const int ox = static_cast<int>(std::lround(double(g.getXMin()) / g.getResolution()));
  const int oy = static_cast<int>(std::lround(double(g.getYMin()) / g.getResolution()));
  const int x = kx - ox, y = ky - oy;
  if (x < 0 || y < 0 || x >= int(g.getSizeX()) || y >= int(g.getSizeY())) return 0;
  return g.getRow(y)[x];
}

}  // namespace

// sigma = 0, and a sigma far below half a raster stretch: every beam's band lies in its end cell,
// so the scan steps the grid's cells with the grid's steps in the grid's order. On SENA with
// icp-slam's section, and on the two simplemaps with rbpf-slam's and pf-localization's.
TEST(MrptGridEstimator, RangeNoiseAsSigmaGoesToZeroIsTheStockGrid) {
  struct Case {
    std::string what, config, prefix;
    std::vector<Frame> frames;
  };
  const std::vector<Case> cases = {
      {"SENA", kSection, "MappingApplication", sena()},
      {"Malaga simplemap", "rbpf-slam/gridmapping_optimal_sampling.ini", "MappingApplication",
       simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz"))},
      {"localization_demo simplemap", "pf-localization/localization_demo.ini", "MetricMap",
       simplemapFrames(dataset("localization_demo.simplemap.gz"))}};
  for (const Case& c : cases)
    for (const std::string extra : {"sensorModel = rangeNoise\nrangeNoiseStd = 0\nrangeNoiseStdPerMeter = 0",
                                    "sensorModel = rangeNoise\nrangeNoiseStd = 0.0001\nrangeNoiseStdPerMeter = 0.00001"}) {
      auto p = pasted(extra, c.config, c.prefix);
      std::size_t scans = 0;
      for (const Frame& f : c.frames)
        for (const auto& o : *f.sf) {
          if (!IS_CLASS(*o, mrpt::obs::CObservation2DRangeScan)) continue;
          const bool ins = p->g->insertObservation(*o, f.pose);
          EXPECT_EQ(p->r->insertObservation(*o, f.pose), ins);
          scans += ins;
        }
      const Figures fr = compareRTree(*p->g, *p->r);
      std::cout << c.what << ", range noise (" << p->r->insertionOptions.rangeNoiseStd << " m + "
                << p->r->insertionOptions.rangeNoiseStdPerMeter << " m/m) in mrpt_grid: " << scans << " scans, "
                << fr.cells << " cells, " << fr.differ << " differ from the stock grid\n";
      EXPECT_GT(scans, 50u);
      EXPECT_EQ(fr.differ, 0u) << c.what;
      EXPECT_EQ(p->r->map().checkInvariants(), "");
    }
}

// sigma = 5 cm + 1 %: the cells far from every reading took the same whole free steps as the
// grid's; those near a reading are graded, on the int8 lattice, and only they hold occupied evidence
// (a reading spread over several cells makes each less sure than the grid's one end cell: fewer
// cells end up occupied, doc/range-noise.md).
TEST(MrptGridEstimator, RangeNoiseGradesOnlyTheBandsOnTheGridsLattice) {
  auto p = pasted("sensorModel = rangeNoise\nrangeNoiseStd = 0.05\nrangeNoiseStdPerMeter = 0.01\nrangeNoiseCutoff = 3");
  const double res = p->g->getResolution();
  std::set<std::pair<int, int>> near;  // cells within the widest band (+1 cell) of an end point
  for (std::size_t i = 0; i < 40 && i < sena().size(); ++i) {
    const Frame& f = sena()[i];
    const auto s = scanOf(f);
    if (!s) continue;
    p->g->insertObservation(*s, f.pose);
    p->r->insertObservation(*s, f.pose);
    const mrpt::poses::CPose3D sensor = f.pose + s->sensorPose;
    for (std::size_t b = 0; b < s->getScanSize(); ++b) {
      if (!s->getScanRangeValidity(b)) continue;
      const double r = s->getScanRange(b), a = s->getScanAngle(b);
      const int w = static_cast<int>(std::ceil(3 * (0.05 + 0.01 * r) / res)) + 2;
      double x, y, z;
      sensor.composePoint(r * std::cos(a), r * std::sin(a), 0, x, y, z);
      const int kx = static_cast<int>(std::floor(x / res)), ky = static_cast<int>(std::floor(y / res));
      for (int dy = -w; dy <= w; ++dy)
        for (int dx = -w; dx <= w; ++dx) near.insert({kx + dx, ky + dy});
    }
  }
  const auto ours = cellsOf(*p->r);
  std::size_t far = 0, far_differ = 0, near_differ = 0, ours_occupied = 0, stock_occupied = 0, far_occupied = 0;
  for (const auto& [k, c] : ours) {
    const int want = stockCell(*p->g, k.first, k.second);
    ours_occupied += c < 0;
    stock_occupied += want < 0;
    if (near.count(k)) {
      near_differ += c != want;
    } else {
      ++far;
      far_differ += c != want;
      far_occupied += c < 0;
    }
  }
  std::cout << "SENA, 40 scans, range noise 5 cm + 1 % in mrpt_grid: " << ours.size() << " cells; " << far
            << " away from the readings, " << far_differ << " of them differ from the stock grid; " << near_differ
            << " near them differ; occupied cells " << ours_occupied << " (stock grid " << stock_occupied << ")\n";
  EXPECT_GT(far, 10000u);
  EXPECT_EQ(far_differ, 0u);
  EXPECT_GT(near_differ, 1000u);
  EXPECT_GT(ours_occupied, 200u);
  EXPECT_EQ(far_occupied, 0u);
  EXPECT_EQ(p->r->gridFrame().size_x, p->g->getSizeX());  // the grid's geometry: bands do not grow it
  EXPECT_EQ(p->r->gridFrame().x_min, p->g->getXMin());
}

// A zero covariance is the certain pose: the stock grid's cells through the uncertain-pose API.
TEST(MrptGridEstimator, PoseBlurWithZeroCovarianceIsTheStockGridOnSena) {
  auto p = pasted("poseUncertainty = on");
  std::size_t scans = 0;
  for (const Frame& f : sena())
    if (const auto s = scanOf(f)) {
      const bool ins = p->g->insertObservation(*s, f.pose);
      EXPECT_EQ(p->r->insertObservation(*s, mrpt::poses::CPose3DPDFGaussian(f.pose)), ins);
      scans += ins;
    }
  const Figures fr = compareRTree(*p->g, *p->r);
  std::cout << "SENA, pose blur with zero covariance in mrpt_grid: " << scans << " scans, " << fr.differ
            << " cells differ from the stock grid\n";
  EXPECT_EQ(fr.differ, 0u);
}

// One scan from an uncertain pose into an empty map: each cell lies between the cells the sigma
// poses give on their own (the mixture of their changes), within the rounding to int8 units; the
// result is on the lattice and differs from the mean pose's scan.
TEST(MrptGridEstimator, PoseBlurMixesTheSigmaPosesOnTheGridsLattice) {
  const Frame& f = sena()[30];
  const auto s = scanOf(f);
  ASSERT_TRUE(s);
  mrpt::math::CMatrixDouble66 cov;
  cov.setZero();
  cov(0, 0) = cov(1, 1) = 0.05 * 0.05;
  cov(3, 3) = mrpt::square(mrpt::DEG2RAD(2.0));
  const mrpt::poses::CPose3DPDFGaussian pdf(f.pose, cov);
  auto blurred = pasted("poseUncertainty = on");
  ASSERT_TRUE(blurred->r->insertObservation(*s, pdf));
  const auto mixed = cellsOf(*blurred->r);
  // The sigma points: +-sqrt(3 lambda) along x, y, yaw (rtog::sigmaPoints), each on its own map.
  std::vector<std::map<std::pair<int, int>, int>> alone;
  for (int axis : {0, 1, 3})
    for (double sign : {-1.0, 1.0}) {
      double d[6] = {0, 0, 0, 0, 0, 0};
      d[axis] = sign * std::sqrt(3.0 * cov(axis, axis));
      const mrpt::poses::CPose3D q(f.pose.x() + d[0], f.pose.y() + d[1], f.pose.z(), f.pose.yaw() + d[3],
                                   f.pose.pitch(), f.pose.roll());
      auto single = pasted();
      ASSERT_TRUE(single->r->insertObservation(*s, q));
      alone.push_back(cellsOf(*single->r));
    }
  auto mean = pasted();
  ASSERT_TRUE(mean->r->insertObservation(*s, f.pose));
  const auto plain = cellsOf(*mean->r);
  std::size_t outside = 0, differ_from_mean = 0;
  for (const auto& [k, c] : mixed) {
    const auto [lo, hi] = cellRange(alone, k);
    outside += c < lo - 1 || c > hi + 1;
    const auto it = plain.find(k);
    differ_from_mean += it == plain.end() || it->second != c;
  }
  std::cout << "SENA scan 30 from an uncertain pose (5 cm, 2 deg) in mrpt_grid: " << mixed.size() << " cells, "
            << outside << " outside their sigma poses' range, " << differ_from_mean << " differ from the mean pose's\n";
  EXPECT_GT(mixed.size(), 1000u);
  EXPECT_EQ(outside, 0u);
  EXPECT_GT(differ_from_mean, 100u);
}

// The mixture's cells live in blocks that the inserting thread keeps between scans, found by a
// table over the grid, or by hash where the grid is too large for the table (8192^2 cells). Neither
// may change a cell: the same blurred scans give the same cells in a thread of its own (nothing
// kept yet), after other blurred maps were built in this thread, and in a grid that a scan 600 m
// away grew past the table's size first.
TEST(MrptGridEstimator, PoseBlurDoesNotDependOnKeptBlocksOrTheGridsSize) {
  mrpt::math::CMatrixDouble66 cov;
  cov.setZero();
  cov(0, 0) = cov(1, 1) = 0.05 * 0.05;
  cov(3, 3) = mrpt::square(mrpt::DEG2RAD(2.0));
  const auto build = [&](bool far_first) {
    auto p = pasted("poseUncertainty = on");
    if (far_first) {
      const mrpt::poses::CPose3D far = sena()[0].pose + mrpt::poses::CPose3D(600, 600, 0, 0, 0, 0);
      EXPECT_TRUE(p->r->insertObservation(*scanOf(sena()[0]), mrpt::poses::CPose3DPDFGaussian(far, cov)));
      EXPECT_GT(std::uint64_t{p->r->gridFrame().size_x} * p->r->gridFrame().size_y, std::uint64_t{1} << 26);
    }
    for (std::size_t i = 0; i < 40 && i < sena().size(); ++i)
      if (const auto s = scanOf(sena()[i])) {
        EXPECT_TRUE(p->r->insertObservation(*s, mrpt::poses::CPose3DPDFGaussian(sena()[i].pose, cov)));
      }
    auto cells = cellsOf(*p->r);
    for (auto it = cells.begin(); it != cells.end();)  // the far scan's cells: 600 m is 12000 cells
      it = it->first.first > 6000 ? cells.erase(it) : std::next(it);
    return cells;
  };
  std::map<std::pair<int, int>, int> alone;
  std::thread([&] { alone = build(false); }).join();
  ASSERT_GT(alone.size(), 10000u);
  const auto far = build(true);
  const auto again = build(false);
  std::cout << "SENA, 40 blurred scans in mrpt_grid: " << alone.size() << " cells in a fresh thread; "
            << (far == alone ? "the same" : "others") << " after a far scan, "
            << (again == alone ? "the same" : "others") << " with kept blocks\n";
  EXPECT_TRUE(far == alone);
  EXPECT_TRUE(again == alone);
}

// A particle filter scores between insertions: the 2D view's tiles are then kept and follow each
// scan's steps (the graded ones too) instead of being made again. The scores after 60 scans must be
// those of a map that made its view once, at the end, from its cells.
TEST(MrptGridEstimator, TheViewFollowsGradedScansAsARebuildWouldMakeIt) {
  for (const bool blur : {false, true}) {
    const std::string extra = "sensorModel = rangeNoise\nrangeNoiseStd = 0.05\nrangeNoiseStdPerMeter = 0.01" +
                              std::string(blur ? "\nposeUncertainty = on" : "");
    auto followed = pasted(extra), rebuilt = pasted(extra);
    mrpt::math::CMatrixDouble66 cov;
    cov.setZero();
    cov(0, 0) = cov(1, 1) = 0.03 * 0.03;
    cov(3, 3) = mrpt::square(mrpt::DEG2RAD(1.0));
    std::vector<std::pair<mrpt::poses::CPose3D, mrpt::obs::CObservation2DRangeScan::Ptr>> done;
    for (std::size_t i = 0; i < 60 && i < sena().size(); ++i) {
      const auto s = scanOf(sena()[i]);
      if (!s) continue;
      const mrpt::poses::CPose3DPDFGaussian pose(sena()[i].pose, blur ? cov : mrpt::math::CMatrixDouble66());
      ASSERT_TRUE(followed->r->insertObservation(*s, pose));
      ASSERT_TRUE(rebuilt->r->insertObservation(*s, pose));
      followed->r->computeObservationLikelihood(*s, sena()[i].pose);  // keeps the tiles
      done.emplace_back(sena()[i].pose, s);
    }
    ASSERT_GT(done.size(), 40u);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < done.size(); i += 4) {
      const mrpt::poses::CPose3D q = done[i].first + mrpt::poses::CPose3D(0.1, -0.05, 0, 0.03, 0, 0);
      differ += followed->r->computeObservationLikelihood(*done[i].second, q) !=
                rebuilt->r->computeObservationLikelihood(*done[i].second, q);
    }
    std::cout << "SENA, 60 graded scans" << (blur ? " from uncertain poses" : "") << ": " << differ
              << " likelihoods differ between the followed view and one made from the cells\n";
    EXPECT_EQ(differ, 0u);
  }
}
