// poseUncertainty (doc/pose-uncertainty.md) through the MRPT class, on real data: a zero
// covariance (or the option off) is the plain insertion bit for bit; synthetic covariances on
// SENA and on the Malaga simplemap give maps whose mean cell entropy rises with the covariance;
// the .ini key, its errors and the archive.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include "map_cells.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using rtog::test::CellValues;
using rtog::test::cellsOf;

namespace {

CRTreeOccupancyGridMap::TInsertionOptions octomapOptions(bool blur) {
  CRTreeOccupancyGridMap::TInsertionOptions io;
  io.sensorModelPreset = "octomap";
  io.poseUncertainty = blur;
  io.threads = 1;
  return io;
}

bool sameCells(const CellValues& a, const CellValues& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].first != b[i].first || std::memcmp(&a[i].second, &b[i].second, sizeof(float)) != 0) return false;
  return true;
}

/// Mean binary entropy [bits] of the known cells.
double meanEntropy(const rtog::OccupancyMap& m) {
  double sum = 0;
  std::int64_t n = 0;
  m.forEachLeaf([&](const rtog::Box& b, float l) {
    const double p = 1.0 / (1.0 + std::exp(-double(l)));
    const double h = p <= 0 || p >= 1 ? 0.0 : -(p * std::log2(p) + (1 - p) * std::log2(1 - p));
    sum += h * double(b.volume());
    n += b.volume();
  });
  return n ? sum / double(n) : 0.0;
}

const mrpt::maps::CSimpleMap& malaga() {
  static const mrpt::maps::CSimpleMap sm = [] {
    mrpt::maps::CSimpleMap s;
    if (!s.loadFromFile(rtog_test::dataset("malaga-cs-fac-building.simplemap.gz"))) throw std::runtime_error("malaga");
    return s;
  }();
  return sm;
}

// SENA's first frames at their odometry poses, each with the planar covariance diag(s^2, s^2, (s/4)^2).
CRTreeOccupancyGridMap senaWithCovariance(double s, bool blur) {
  CRTreeOccupancyGridMap m(0.05, octomapOptions(blur));
  for (const auto& f : rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 40)) {
    mrpt::poses::CPosePDFGaussian pdf(mrpt::poses::CPose2D(f.pose));
    pdf.cov.setZero();
    pdf.cov(0, 0) = pdf.cov(1, 1) = s * s;
    pdf.cov(2, 2) = s * s / 16;
    for (const auto& obs : *f.sf) m.insertObservation(*obs, pdf);
  }
  return m;
}

}  // namespace

TEST(PoseUncertainty, AZeroCovarianceOrTheOptionOffIsThePlainInsertion) {
  CRTreeOccupancyGridMap plain(0.05, octomapOptions(false)), zero(0.05, octomapOptions(true)),
      off(0.05, octomapOptions(false));
  for (const auto& f : rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 40)) {
    mrpt::poses::CPose3DPDFGaussian certain(f.pose), uncertain(f.pose);
    certain.cov.setZero();
    uncertain.cov.setIdentity();
    uncertain.cov *= 0.01;
    for (const auto& obs : *f.sf) {
      plain.insertObservation(*obs, f.pose);
      zero.insertObservation(*obs, certain);
      off.insertObservation(*obs, uncertain);  // poseUncertainty off: the mean
    }
  }
  const CellValues ref = cellsOf(plain.map());
  EXPECT_GT(ref.size(), 10000u);
  EXPECT_TRUE(sameCells(ref, cellsOf(zero.map())));
  EXPECT_TRUE(sameCells(ref, cellsOf(off.map())));
}

TEST(PoseUncertainty, SyntheticCovariancesOnSenaSoftenTheMapMonotonically) {
  double last = -1;
  std::size_t last_cells = 0;
  for (const double s : {0.0, 0.02, 0.05, 0.1, 0.2}) {
    const CRTreeOccupancyGridMap m = senaWithCovariance(s, true);
    ASSERT_EQ(m.map().checkInvariants(), "");
    const double h = meanEntropy(m.map());
    const auto cells = static_cast<std::size_t>(m.map().cellCount());
    EXPECT_GT(h, last) << "sigma " << s;
    EXPECT_GT(cells, last_cells) << "sigma " << s;  // the blur spreads the evidence
    last = h;
    last_cells = cells;
  }
}

// Debian's Malaga simplemap stores every pose with a zero covariance: with poseUncertainty on it
// loads bit for bit as at the means (as MRPT's own loader does); with synthetic covariances
// (diag(s^2, s^2, 0, (s/4)^2, 0, 0)) the map softens as s grows. The covariances of a real SLAM run
// (rbpf-slam's particle paths) are the app test rbpf_slam's (tests/mrpt/app_tests.py).
TEST(PoseUncertainty, TheMalagaSimplemapAtItsZeroCovariancesAndWithSyntheticOnes) {
  const auto& sm = malaga();
  std::size_t uncertain = 0;
  for (const auto& pair : sm) {
    mrpt::poses::CPose3DPDFGaussian g;
    g.copyFrom(*pair.pose);
    uncertain += g.cov.trace() > 0;
  }
  EXPECT_EQ(uncertain, 0u);
  CRTreeOccupancyGridMap on(0.05, octomapOptions(true)), mrptLoader(0.05, octomapOptions(false));
  on.loadFromSimpleMap(sm);
  static_cast<mrpt::maps::CMetricMap&>(mrptLoader).loadFromSimpleMap(sm);  // MRPT's: at the means
  EXPECT_GT(on.map().cellCount(), 100000);
  EXPECT_TRUE(sameCells(cellsOf(on.map()), cellsOf(mrptLoader.map())));
  double last = meanEntropy(on.map());
  for (const double s : {0.02, 0.05, 0.1}) {
    mrpt::maps::CSimpleMap noisy;
    for (const auto& pair : sm) {
      auto g = mrpt::poses::CPose3DPDFGaussian::Create();
      g->copyFrom(*pair.pose);
      g->cov(0, 0) = g->cov(1, 1) = s * s;
      g->cov(3, 3) = s * s / 16;
      noisy.insert(g, pair.sf);
    }
    CRTreeOccupancyGridMap blurred(0.05, octomapOptions(true));
    blurred.loadFromSimpleMap(noisy);
    ASSERT_EQ(blurred.map().checkInvariants(), "");
    const double h = meanEntropy(blurred.map());
    EXPECT_GT(h, last) << "sigma " << s;
    last = h;
  }
}

TEST(PoseUncertainty, TheIniKeyReadsOffOrOnAndIsChecked) {
  auto on = rtog_test::mapFromIni("sensorModelPreset=octomap\nposeUncertainty=on\n");
  ASSERT_TRUE(on);
  EXPECT_TRUE(on->insertionOptions.poseUncertainty);
  auto off = rtog_test::mapFromIni("sensorModelPreset=octomap\n");
  EXPECT_FALSE(off->insertionOptions.poseUncertainty);
  // Both presets take it (mrpt_grid: on the grid's raster, test_mrpt_grid_estimator.cpp).
  EXPECT_TRUE(rtog_test::mapFromIni("poseUncertainty=on\n")->insertionOptions.poseUncertainty);
  for (const char* bad : {"sensorModelPreset=octomap\nposeUncertainty=maybe\n", "poseUncertainty=maybe\n"}) {
    try {
      rtog_test::mapFromIni(bad);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("poseUncertainty"), std::string::npos) << e.what();
    }
  }
  // Written and read back, and kept in the map's archive.
  mrpt::config::CConfigFileMemory cfg;
  on->insertionOptions.saveToConfigFile(cfg, "s");
  CRTreeOccupancyGridMap::TInsertionOptions back;
  back.loadFromConfigFile(cfg, "s");
  EXPECT_TRUE(back.poseUncertainty);
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << *on;
  buf.Seek(0);
  auto read = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(ar.ReadObject());
  ASSERT_TRUE(read);
  EXPECT_TRUE(read->insertionOptions.poseUncertainty);
}

TEST(PoseUncertainty, ACovarianceThatIsNotOneIsRefusedAndChangesNothing) {
  CRTreeOccupancyGridMap m = senaWithCovariance(0.05, true);
  const CellValues before = cellsOf(m.map());
  const auto frames = rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 1);
  mrpt::poses::CPose3DPDFGaussian bad(frames[0].pose);
  bad.cov.setIdentity();
  bad.cov(0, 0) = -1;
  EXPECT_THROW(m.insertObservation(**frames[0].sf->begin(), bad), std::invalid_argument);
  bad.cov(0, 0) = std::nan("");
  EXPECT_THROW(m.insertObservation(**frames[0].sf->begin(), bad), std::invalid_argument);
  EXPECT_TRUE(sameCells(before, cellsOf(m.map())));
}
