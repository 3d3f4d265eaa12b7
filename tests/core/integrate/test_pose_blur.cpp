// Pose uncertainty blurred into the update (doc/pose-uncertainty.md): the sigma-point set has
// the Gaussian's moments; one pose is the plain update bit for bit; on real frames every cell
// holds the mixture of what the plain update from each pose alone gives it, computed here from
// maps built pose by pose; the map does not depend on the thread count; bad input changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "rtog/core/occupancy_map.hpp"
#include "map_cells.hpp"
#include "test_support.hpp"

using namespace rtog;

namespace {

using test::CellValues;
using test::cellsOf;

MapParams params() {
  MapParams p;
  p.resolution = 0.1;
  p.merge = MergePolicy::Equal;
  return p;
}

// A TUM frame moved by a small rigid motion about its origin: the frame as seen from a pose
// off the estimate.
struct MovedScan {
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> points;
};
MovedScan moved(const image::WorldScan& s, double dx, double dy, double yaw) {
  const Eigen::Isometry3d t = Eigen::Translation3d(s.origin + Eigen::Vector3d(dx, dy, 0.0)) *
                              Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Translation3d(-s.origin);
  MovedScan out{t * s.origin, {}};
  for (const auto& p : s.points) out.points.push_back((t * p.cast<double>()).cast<float>());
  return out;
}

std::vector<WeightedScan> weighted(const std::vector<MovedScan>& scans, const std::vector<double>& w) {
  std::vector<WeightedScan> out;
  for (std::size_t i = 0; i < scans.size(); ++i)
    out.push_back(WeightedScan{w[i], scans[i].origin, scans[i].points.data(), scans[i].points.size(), nullptr});
  return out;
}

InsertParams model(SensorModel m) {
  InsertParams ip;
  ip.model = m;
  ip.max_range = 4.0;
  ip.threads = 1;
  return ip;
}

double sigmoid(double l) { return 1.0 / (1.0 + std::exp(-l)); }

// The same cells with bit-identical values (not memcmp of the pairs: their padding is not data).
bool sameCells(const CellValues& a, const CellValues& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].first != b[i].first || std::memcmp(&a[i].second, &b[i].second, sizeof(float)) != 0) return false;
  return true;
}

}  // namespace

TEST(SigmaPoints, HaveTheGaussiansMeanAndCovariance) {
  Eigen::MatrixXd cov(3, 3);
  cov << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.0025;
  const auto pts = sigmaPoints(cov);
  ASSERT_EQ(pts.size(), 6u);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(3);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(3, 3);
  double sum = 0;
  for (const auto& p : pts) {
    EXPECT_GT(p.weight, 0.0);
    sum += p.weight;
    mean += p.weight * p.offset;
    c += p.weight * p.offset * p.offset.transpose();
  }
  EXPECT_NEAR(sum, 1.0, 1e-15);
  EXPECT_LT(mean.norm(), 1e-15);
  EXPECT_LT((c - cov).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(SigmaPoints, ARankDeficientCovarianceSamplesOnlyItsDirections) {
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(6, 6);  // a planar pose's (x, y, yaw) in six dimensions
  cov(0, 0) = 0.01, cov(1, 1) = 0.02, cov(3, 3) = 0.001, cov(0, 1) = cov(1, 0) = 0.005;
  const auto pts = sigmaPoints(cov);
  ASSERT_EQ(pts.size(), 6u);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(6, 6);
  for (const auto& p : pts) {
    c += p.weight * p.offset * p.offset.transpose();
    EXPECT_EQ(p.offset[2], 0.0);  // z, pitch and roll stay at the mean
  }
  EXPECT_LT((c - cov).cwiseAbs().maxCoeff(), 1e-15);
  const auto zero = sigmaPoints(Eigen::MatrixXd::Zero(6, 6));
  ASSERT_EQ(zero.size(), 1u);
  EXPECT_EQ(zero[0].weight, 1.0);
  EXPECT_TRUE(zero[0].offset.isZero(0.0));
}

TEST(SigmaPoints, RefuseMatricesThatAreNotCovariances) {
  Eigen::MatrixXd neg = Eigen::MatrixXd::Identity(3, 3);
  neg(1, 1) = -0.5;
  EXPECT_THROW(sigmaPoints(neg), std::invalid_argument);
  Eigen::MatrixXd asym = Eigen::MatrixXd::Identity(3, 3);
  asym(0, 1) = 0.3;
  EXPECT_THROW(sigmaPoints(asym), std::invalid_argument);
  Eigen::MatrixXd nan = Eigen::MatrixXd::Identity(2, 2);
  nan(0, 0) = std::nan("");
  EXPECT_THROW(sigmaPoints(nan), std::invalid_argument);
  EXPECT_THROW(sigmaPoints(Eigen::MatrixXd::Identity(2, 3)), std::invalid_argument);
}

TEST(PoseBlur, OnePoseIsThePlainUpdateBitForBit) {
  const auto frames = test::loadTumScans(8);
  for (const SensorModel m : {SensorModel::BeamBased, SensorModel::BeamEndPoint, SensorModel::RangeNoise}) {
    OccupancyMap plain(params()), blurred(params());
    for (const auto& f : frames) {
      plain.insertPointCloud(f.origin, f.points, model(m));
      const WeightedScan one{0.5, f.origin, f.points.data(), f.points.size(), nullptr};
      blurred.insertBlurred(&one, 1, model(m));
    }
    EXPECT_TRUE(sameCells(cellsOf(plain), cellsOf(blurred))) << toString(m);
  }
}

// The oracle: a map per pose, built by the plain update alone on an empty map, gives P_i of each
// cell (the prior where it has none); the blurred map must hold logit(sum w_i P_i), clamped.
TEST(PoseBlur, EachCellHoldsTheMixtureOfThePlainUpdatesFromEachPose) {
  const auto frames = test::loadTumScans(8);
  ASSERT_FALSE(frames.empty());
  const std::vector<MovedScan> poses = {moved(frames[0], 0.07, 0.0, 0.0), moved(frames[0], -0.07, 0.0, 0.0),
                                        moved(frames[0], 0.0, 0.05, 0.02), moved(frames[0], 0.0, -0.05, -0.02)};
  const std::vector<double> w = {0.1, 0.2, 0.3, 0.4};
  for (const SensorModel m : {SensorModel::BeamBased, SensorModel::BeamEndPoint, SensorModel::RangeNoise}) {
    const InsertParams ip = model(m);
    OccupancyMap blurred(params());
    blurred.insertBlurred(weighted(poses, w), ip);
    ASSERT_EQ(blurred.checkInvariants(), "");
    const LogOddsModel& lm = blurred.logOddsModel();
    std::map<std::uint64_t, double> sum;  // cell -> sum w_i (P_i - P0)
    for (std::size_t i = 0; i < poses.size(); ++i) {
      OccupancyMap one(params());
      one.insertPointCloud(poses[i].origin, poses[i].points, ip);
      for (const auto& [k, v] : cellsOf(one)) sum[k] += w[i] * (sigmoid(v) - sigmoid(lm.prior()));
    }
    const CellValues got = cellsOf(blurred);
    ASSERT_EQ(got.size(), sum.size()) << toString(m);
    double worst = 0;
    std::size_t i = 0;
    for (const auto& [k, s] : sum) {
      ASSERT_EQ(got[i].first, k);
      const double p = sigmoid(lm.prior()) + s;
      const double want = std::min<double>(std::max<double>(std::log(p / (1 - p)), lm.clampMin()), lm.clampMax());
      worst = std::max(worst, std::abs(got[i].second - want));
      ++i;
    }
    EXPECT_LT(worst, 2e-6) << toString(m);
    // The blur is real: the map is not any one pose's.
    OccupancyMap first(params());
    first.insertPointCloud(poses[0].origin, poses[0].points, ip);
    EXPECT_GT(got.size(), cellsOf(first).size()) << toString(m);
  }
}

TEST(PoseBlur, IdenticalPosesGiveThePlainValues) {
  const auto frames = test::loadTumScans(8);
  const MovedScan s = moved(frames[1], 0, 0, 0);
  OccupancyMap plain(params()), blurred(params());
  plain.insertPointCloud(s.origin, s.points, model(SensorModel::BeamBased));
  blurred.insertBlurred(weighted({s, s, s}, {1, 1, 1}), model(SensorModel::BeamBased));
  const CellValues a = cellsOf(plain), b = cellsOf(blurred);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first);
    EXPECT_NEAR(a[i].second, b[i].second, 1e-5);
  }
}

TEST(PoseBlur, TheMapDoesNotDependOnTheThreadCount) {
  const auto frames = test::loadTumScans(8);
  std::vector<MovedScan> poses;
  for (int i = 0; i < 6; ++i) poses.push_back(moved(frames[2], 0.03 * (i - 2.5), 0.01 * i, 0.01 * (i % 3 - 1)));
  const std::vector<double> w(6, 1.0);
  std::map<SensorModel, CellValues> ref;
  for (const int threads : {1, 2, 5}) {
    for (const SensorModel m : {SensorModel::BeamBased, SensorModel::RangeNoise}) {
      InsertParams ip = model(m);
      ip.threads = threads;
      OccupancyMap map(params());
      map.insertBlurred(weighted(poses, w), ip);
      const CellValues c = cellsOf(map);
      if (ref[m].empty()) ref[m] = c;
      EXPECT_TRUE(sameCells(c, ref[m])) << toString(m) << ", " << threads << " threads";
    }
  }
}

TEST(PoseBlur, BadWeightsOrOriginsChangeNothing) {
  const auto frames = test::loadTumScans(8);
  OccupancyMap map(params());
  map.insertPointCloud(frames[0].origin, frames[0].points, model(SensorModel::BeamBased));
  const CellValues before = cellsOf(map);
  const MovedScan s = moved(frames[1], 0, 0, 0);
  for (const double bad : {0.0, -1.0, std::nan(""), HUGE_VAL})
    EXPECT_THROW(map.insertBlurred(weighted({s, s}, {1.0, bad}), model(SensorModel::BeamBased)), std::invalid_argument);
  MovedScan far = s;
  far.origin = Eigen::Vector3d(1e12, 0, 0);
  EXPECT_THROW(map.insertBlurred(weighted({s, far}, {1.0, 1.0}), model(SensorModel::BeamBased)), std::out_of_range);
  EXPECT_TRUE(sameCells(before, cellsOf(map)));
}
