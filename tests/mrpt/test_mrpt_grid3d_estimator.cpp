// The estimator's graded models in the mrpt_grid preset's 3D sections (mrpt_grid3d::insertRays)
// against MRPT's own COccupancyGridMap3D on tests_rgbd.rawlog's depth frames: with sigma -> 0 and
// a certain pose they are the grid, voxel for voxel; otherwise their changes land on the grid's
// int8 lattice near the readings only (range noise) and mix the sigma poses' changes (pose blur).
// And a 2D section's 3D observations, which take the core's graded rules with the grid's unit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "grid3d_fidelity.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

const char* kBox = "resolution=0.10\nmin_x=-2\nmax_x=6\nmin_y=-4\nmax_y=4\nmin_z=-2\nmax_z=3";

std::vector<mrpt::obs::CObservation::Ptr> depthFrames() {
  std::vector<mrpt::obs::CObservation::Ptr> out;
  for (const auto& o : observationsOf(dataset("tests_rgbd.rawlog")))
    if (IS_CLASS(*o, mrpt::obs::CObservation3DRangeScan)) out.push_back(o);
  if (out.empty()) throw std::runtime_error("tests_rgbd.rawlog holds no depth frame");
  return out;
}

mrpt::poses::CPose3D poseOf(std::size_t i) { return mrpt::poses::CPose3D(0.05 * double(i), 0, 0, 0.02 * double(i), 0, 0); }

/// Every leaf value an int8 cell; the cells by lattice key.
std::map<std::array<int, 3>, int> cellsOf(const CRTreeOccupancyGridMap& m) {
  std::map<std::array<int, 3>, int> out;
  std::size_t off_lattice = 0;
  m.map().forEachLeaf([&](const rtog::Box& b, float v) {
    const float c = -v * 16.0f;
    off_lattice += c != std::round(c) || std::abs(c) > 127.0f;
    rtog::forEachCell(b, [&](const rtog::Key& k) { out[{k.x, k.y, k.z}] = static_cast<int>(std::lround(c)); });
  });
  EXPECT_EQ(off_lattice, 0u) << "leaves whose value is no int8 cell";
  return out;
}

}  // namespace

TEST(MrptGrid3DEstimator, RangeNoiseAsSigmaGoesToZeroAndACertainPoseAreTheStockGrid) {
  for (const std::string extra : {"sensorModel=rangeNoise\nrangeNoiseStd=0\nrangeNoiseStdPerMeter=0",
                                  "sensorModel=rangeNoise\nrangeNoiseStd=0.0001\nrangeNoiseStdPerMeter=0.00001",
                                  "poseUncertainty=on"}) {
    Pair p = makePair(kBox, extra);
    const auto frames = depthFrames();
    for (std::size_t i = 0; i < frames.size(); ++i) {
      p.stock->insertObservation(*frames[i], poseOf(i));
      ASSERT_TRUE(p.ours->insertObservation(*frames[i], mrpt::poses::CPose3DPDFGaussian(poseOf(i))));
    }
    std::string what = extra;
    std::replace(what.begin(), what.end(), '\n', ' ');
    EXPECT_EQ(differingCells(p, "tests_rgbd.rawlog in a 3D section, " + what), 0u);
  }
}

// sigma = 2 cm + 1 %: voxels farther than the band (+2 cells) from every reading took the grid's
// whole free steps; those near a reading are graded, on the lattice.
TEST(MrptGrid3DEstimator, RangeNoiseGradesOnlyTheBandsOnTheGridsLattice) {
  Pair p = makePair(kBox, "sensorModel=rangeNoise\nrangeNoiseStd=0.02\nrangeNoiseStdPerMeter=0.01");
  const rtog::TGridFrame3D& f = p.ours->gridFrame3D();
  const rtog::Key o{static_cast<int>(std::lround(f.x_min / f.resolution)), static_cast<int>(std::lround(f.y_min / f.resolution)),
                    static_cast<int>(std::lround(f.z_min / f.resolution))};
  std::vector<char> near(std::size_t{f.size_x} * f.size_y * f.size_z, 0);
  const auto frames = depthFrames();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    p.stock->insertObservation(*frames[i], poseOf(i));
    ASSERT_TRUE(p.ours->insertObservation(*frames[i], poseOf(i)));
    rtog::ObservationBeams b;
    ASSERT_TRUE(p.ours->extractBeams(*frames[i], poseOf(i), b, true));
    for (const auto& q : b.points) {
      const double r = (q.cast<double>() - b.origin).norm();
      const int w = static_cast<int>(std::ceil(3 * (0.02 + 0.01 * r) / f.resolution)) + 2;
      const int cx = int(std::floor((q.x() - f.x_min) / f.resolution)), cy = int(std::floor((q.y() - f.y_min) / f.resolution)),
                cz = int(std::floor((q.z() - f.z_min) / f.resolution));
      for (int z = std::max(0, cz - w); z <= std::min(int(f.size_z) - 1, cz + w); ++z)
        for (int y = std::max(0, cy - w); y <= std::min(int(f.size_y) - 1, cy + w); ++y)
          for (int x = std::max(0, cx - w); x <= std::min(int(f.size_x) - 1, cx + w); ++x)
            near[(std::size_t(z) * f.size_y + std::size_t(y)) * f.size_x + std::size_t(x)] = 1;
    }
  }
  std::size_t far = 0, far_differ = 0, near_differ = 0;
  for (const auto& [k, c] : cellsOf(*p.ours)) {
    const int cx = k[0] - o.x, cy = k[1] - o.y, cz = k[2] - o.z;
    const int want = *p.stock->m_grid.cellByIndex(unsigned(cx), unsigned(cy), unsigned(cz));
    if (near[(std::size_t(cz) * f.size_y + std::size_t(cy)) * f.size_x + std::size_t(cx)]) {
      near_differ += c != want;
    } else {
      ++far;
      far_differ += c != want;
    }
  }
  std::cout << "tests_rgbd.rawlog, range noise 2 cm + 1 % in a 3D section: " << far << " voxels away from the readings, "
            << far_differ << " of them differ from the stock grid; " << near_differ << " near them differ\n";
  EXPECT_GT(far, 500u);
  EXPECT_EQ(far_differ, 0u);
  EXPECT_GT(near_differ, 500u);
}

// One depth frame from an uncertain pose: each voxel between the voxels its sigma poses give on
// their own (within one unit of rounding), except near the bounds, where the grid saturates and a
// pose's change is the sum of its steps (PoseMixture): not compared there, and allowed in one
// voxel in two hundred whose steps from one pose passed a bound on the way.
TEST(MrptGrid3DEstimator, PoseBlurMixesTheSigmaPosesOnTheGridsLattice) {
  const auto frame = depthFrames().front();
  mrpt::math::CMatrixDouble66 cov;
  cov.setZero();
  cov(0, 0) = cov(1, 1) = 0.03 * 0.03;
  cov(3, 3) = mrpt::square(mrpt::DEG2RAD(2.0));
  const mrpt::poses::CPose3D mean = poseOf(3);
  Pair blurred = makePair(kBox, "poseUncertainty=on");
  ASSERT_TRUE(blurred.ours->insertObservation(*frame, mrpt::poses::CPose3DPDFGaussian(mean, cov)));
  const auto mixed = cellsOf(*blurred.ours);
  std::vector<std::map<std::array<int, 3>, int>> alone;
  for (int axis : {0, 1, 3})
    for (double sign : {-1.0, 1.0}) {
      double d[6] = {0, 0, 0, 0, 0, 0};
      d[axis] = sign * std::sqrt(3.0 * cov(axis, axis));
      Pair single = makePair(kBox, "");
      ASSERT_TRUE(single.ours->insertObservation(
          *frame, mrpt::poses::CPose3D(mean.x() + d[0], mean.y() + d[1], mean.z(), mean.yaw() + d[3], mean.pitch(), mean.roll())));
      alone.push_back(cellsOf(*single.ours));
    }
  std::size_t outside = 0, partial = 0, saturated = 0;
  for (const auto& [k, c] : mixed) {
    const auto [lo, hi] = cellRange(alone, k);
    if (std::max(std::abs(lo), std::abs(hi)) > 127 - 20) {  // within a few steps of a bound
      ++saturated;
      continue;
    }
    outside += c < lo - 1 || c > hi + 1;
    partial += c != lo && c != hi;
  }
  std::cout << "tests_rgbd frame from an uncertain pose (3 cm, 2 deg) in a 3D section: " << mixed.size() << " voxels, "
            << outside << " outside their sigma poses' range, " << partial << " strictly between, " << saturated
            << " near a bound (not compared)\n";
  EXPECT_GT(mixed.size(), 1000u);
  EXPECT_GT(mixed.size() - saturated, 500u);
  EXPECT_LE(outside * 200, mixed.size() - saturated);
  EXPECT_GT(partial, 100u);
}

// A 2D section's depth frames (which COccupancyGridMap2D does not take) go through the core's
// rules: with range noise and from an uncertain pose their graded changes are whole int8 units.
TEST(MrptGrid3DEstimator, TheCoresGradedRulesInA2DSectionStayOnTheLattice) {
  const auto frames = depthFrames();
  mrpt::math::CMatrixDouble66 cov;
  cov.setZero();
  cov(0, 0) = cov(1, 1) = 0.03 * 0.03;
  for (const std::string opts : {"sensorModel=rangeNoise\nrangeNoiseStd=0.03\n", "poseUncertainty=on\n",
                                 "sensorModel=rangeNoise\nposeUncertainty=on\n"}) {
    auto m = mapFromIni("resolution=0.05\n" + opts);
    ASSERT_TRUE(m);
    for (std::size_t i = 0; i < frames.size(); ++i)
      ASSERT_TRUE(m->insertObservation(*frames[i], mrpt::poses::CPose3DPDFGaussian(poseOf(i), cov)));
    const auto cells = cellsOf(*m);
    std::set<int> values;
    for (const auto& [k, c] : cells) values.insert(c);
    std::string what = opts.substr(0, opts.size() - 1);
    std::replace(what.begin(), what.end(), '\n', ' ');
    std::cout << what << " in a 2D section, " << frames.size() << " depth frame(s): " << cells.size() << " cells, "
              << values.size() << " distinct int8 values\n";
    EXPECT_GT(cells.size(), 1000u);
    EXPECT_GT(values.size(), 3u);  // graded, not only the whole steps
  }
}
