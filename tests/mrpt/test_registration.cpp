// Registration before fusion (rtog/mrpt/map_registration.h) on real logs: different data (the
// first and the second part of the Malaga simplemap, the second built in a frame moved by a known
// offset) registered back to the offset; maps that already agree (chunks of one log, a copy) at
// the identity with a usable covariance; maps that share nothing refused; and the fusion blurred
// by the covariance the registration returned. The covariance's calibration over 32 trials is in
// test_registration_calibration.cpp.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>

#include "map_cells.hpp"
#include "registration_helpers.hpp"

using namespace rtog_test;
using mrpt::poses::CPose3D;

namespace {

std::vector<PosedFrame> malaga() { return simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz")); }

void report(const char* name, const rtog::TMapRegistration& r, const CPose3D& truth) {
  const Eigen::Vector3d e = registrationError(r, truth);
  const Eigen::Matrix3d c = planarCov(r);
  std::printf("%s: %s; error %.3f m, %.3f m, %.3f deg; sigma %.4f m, %.4f m, %.4f deg; d2 %.2f; goodness %.3f, "
              "%zu / %zu cells, rms %.3f m\n",
              name, r.converged ? "registered" : r.failure.c_str(), e.x(), e.y(), e.z() * 180 / M_PI,
              std::sqrt(c(0, 0)), std::sqrt(c(1, 1)), std::sqrt(c(2, 2)) * 180 / M_PI, mahalanobis2(r, truth),
              r.goodness, r.pointsA, r.pointsB, r.rmsResidual);
}

/// A planar covariance: of x, y and yaw only, symmetric, positive definite, finite.
void expectPlanarCovariance(const rtog::TMapRegistration& r) {
  const Eigen::Matrix<double, 6, 6> cov = r.pose.cov.asEigen();
  EXPECT_TRUE(cov.allFinite());
  EXPECT_LT((cov - cov.transpose()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(planarCov(r)).eigenvalues().minCoeff(), 0.0);
  for (const int d : {2, 4, 5}) EXPECT_EQ(cov.row(d).cwiseAbs().maxCoeff(), 0.0) << "z, pitch, roll";
}

}  // namespace

// Malaga's CS building (a simplemap of corrected poses): its first half in time against its
// second, moved by -4 m, 1.5 m and -25 degrees, all headings searched. Different scans of one
// building: found within centimetres, the error inside the reported 2-sigma ellipsoid.
TEST(RegisterMaps, MalagaHalvesMovedByAKnownOffset) {
  const auto frames = malaga();
  ASSERT_GT(frames.size(), 50u);
  const std::size_t half = frames.size() / 2;
  const CPose3D truth(-4.0, 1.5, 0.0, -25.0 * M_PI / 180, 0, 0);
  const auto a = buildPart(frames, 0, half), b = buildPart(frames, half, frames.size(), truth);
  const rtog::TMapRegistration r = rtog::registerMaps(*a, *b);
  report("Malaga halves", r, truth);
  ASSERT_TRUE(r.converged) << r.failure;
  const Eigen::Vector3d e = registrationError(r, truth);
  EXPECT_LT(std::hypot(e.x(), e.y()), 0.1);
  EXPECT_LT(std::fabs(e.z()) * 180 / M_PI, 0.5);
  EXPECT_GT(r.goodness, 0.4);
  EXPECT_LE(mahalanobis2(r, truth), kTwoSigma3Dof);
  expectPlanarCovariance(r);
}

// Maps that already agree: two overlapping chunks of one log in one frame (the chunk workflow of
// doc/fusion.md) and a map against its copy. CICP ends where it starts there and its covariance
// is the placeholder 1e6 I (1000 m, 57296 degrees), which blurred the fused map over kilometres;
// they must be registered at the identity with a covariance of centimetres.
TEST(RegisterMaps, MapsThatAlreadyAgreeAreFoundAtTheIdentityWithACentimetreCovariance) {
  const auto frames = malaga();
  const auto a = buildPart(frames, 0, 60), b = buildPart(frames, 40, frames.size());
  for (const auto& [name, other] : {std::pair{"chunks [0, 60) and [40, 99)", b}, std::pair{"a copy", a}}) {
    const rtog::TMapRegistration r = rtog::registerMaps(*a, *other);
    report(name, r, CPose3D());
    ASSERT_TRUE(r.converged) << name << ": " << r.failure;
    const Eigen::Vector3d e = registrationError(r, CPose3D());
    EXPECT_LT(std::hypot(e.x(), e.y()), 0.05) << name;
    EXPECT_LT(std::fabs(e.z()) * 180 / M_PI, 0.2) << name;
    expectPlanarCovariance(r);
    const Eigen::Matrix3d c = planarCov(r);
    EXPECT_LT(std::sqrt(std::max(c(0, 0), c(1, 1))), 0.1) << name;
    EXPECT_LT(std::sqrt(c(2, 2)) * 180 / M_PI, 1.0) << name;
    EXPECT_LE(mahalanobis2(r, CPose3D()), kTwoSigma3Dof) << name;
  }
}

// Maps that do not overlap where the search reaches (the second half of Malaga, built in a frame
// 100 m away, searched around no guess): no registration (not a heading of -180 degrees with a
// zero covariance, as before), with the reason.
TEST(RegisterMaps, MapsThatDoNotOverlapAreNotRegistered) {
  const auto frames = malaga();
  const std::size_t half = frames.size() / 2;
  const auto a = buildPart(frames, 0, half), b = buildPart(frames, half, frames.size(), CPose3D(100, 0, 0, 0, 0, 0));
  const rtog::TMapRegistration r = rtog::registerMaps(*a, *b);
  report("Malaga halves 100 m apart", r, CPose3D(100, 0, 0, 0, 0, 0));
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.failure.find("share too little"), std::string::npos) << r.failure;
  // Bad options and a map without cells are refused by name.
  rtog::TMapRegistrationOptions bad;
  bad.headingStepDeg = 0;
  EXPECT_THROW(rtog::registerMaps(*a, *b, bad), std::invalid_argument);
  bad = {}, bad.minGoodness = 2;
  EXPECT_THROW(rtog::registerMaps(*a, *b, bad), std::invalid_argument);
  bad = {}, bad.headingSpanDeg = 0;
  EXPECT_THROW(rtog::registerMaps(*a, *b, bad), std::invalid_argument);
  bad = {}, bad.endDistance = -1;
  EXPECT_THROW(rtog::registerMaps(*a, *b, bad), std::invalid_argument);
  EXPECT_THROW(rtog::registerMaps(*a, rtog::CRTreeOccupancyGridMap(0.05)), std::runtime_error);
}

// Fusing with the covariance the registration returned blurs the other map by it: a zero
// covariance is the plain fusion at the mean cell for cell; the registered one spreads the second
// map's walls (more cells, the occupied ones less certain), and four times it spreads them more.
TEST(RegisterMaps, FusingWithTheRegisteredCovarianceBlursByIt) {
  const auto frames = malaga();
  const std::size_t half = frames.size() / 2;
  const CPose3D truth(-4.0, 1.5, 0.0, -25.0 * M_PI / 180, 0, 0);
  const auto a = buildPart(frames, 0, half), b = buildPart(frames, half, frames.size(), truth);
  const rtog::TMapRegistration r = rtog::registerMaps(*a, *b);
  ASSERT_TRUE(r.converged) << r.failure;
  rtog::CRTreeOccupancyGridMap plain(*a), certain(*a), blurred(*a), wider(*a);
  plain.fuse(*b, r.pose.mean);
  mrpt::poses::CPose3DPDFGaussian zero = r.pose, four = r.pose;
  zero.cov.setZero();
  four.cov *= 4.0;
  rtog::fuseUncertain(certain, *b, zero);
  EXPECT_EQ(rtog::test::cellsOf(certain.map()), rtog::test::cellsOf(plain.map()));
  rtog::fuseUncertain(blurred, *b, r.pose);
  rtog::fuseUncertain(wider, *b, four);
  EXPECT_EQ(blurred.map().checkInvariants(), "");
  const auto cp = rtog::test::cellsOf(plain.map()), cb = rtog::test::cellsOf(blurred.map()),
             cw = rtog::test::cellsOf(wider.map());
  const auto meanOccupied = [](const rtog::test::CellValues& c) {
    double s = 0;
    std::size_t n = 0;
    for (const auto& [k, v] : c)
      if (v > 0) s += v, ++n;
    return s / double(n);
  };
  std::printf("plain fusion %zu cells (mean occupied log-odds %.3f), registered covariance %zu (%.3f), "
              "four times it %zu (%.3f)\n",
              cp.size(), meanOccupied(cp), cb.size(), meanOccupied(cb), cw.size(), meanOccupied(cw));
  EXPECT_GT(cb.size(), cp.size());
  EXPECT_GT(cw.size(), cb.size());
  EXPECT_LT(meanOccupied(cb), meanOccupied(cp));
  EXPECT_LT(meanOccupied(cw), meanOccupied(cb));
}
