// The registration's covariance against its errors (doc/fusion.md, "Registration"): parts of two
// real logs, the second built in a frame moved by a random known offset, registered back from a
// guess near it; the errors must lie in the reported covariance's 2-sigma ellipsoid
// (registration_helpers.hpp) in at least 90 % of the trials.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "registration_helpers.hpp"

using namespace rtog_test;
using mrpt::poses::CPose3D;

// 32 trials, seed 37: SENA's frames in two random halves, and the Malaga CS building (corrected
// poses) as a first and a second part split at random, the second moved by up to 5 m and 30
// degrees.
TEST(RegistrationCovariance, TheErrorsOfThirtyTwoTrialsLieInItsTwoSigmaEllipsoid) {
  const auto sena = loadOdometryFrames(dataset(kSena));
  const auto malaga = simplemapFrames(dataset("malaga-cs-fac-building.simplemap.gz"));
  ASSERT_GT(sena.size(), 200u);
  ASSERT_GT(malaga.size(), 80u);
  std::mt19937 rng(37);
  const auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  const auto normal = [&](double s) { return std::normal_distribution<double>(0.0, s)(rng); };
  constexpr int kTrials = 32;
  int inside = 0;
  double worst_t = 0, worst_yaw = 0, sum_d2 = 0;
  for (int t = 0; t < kTrials; ++t) {
    const bool on_sena = t % 2 == 0;
    const auto& frames = on_sena ? sena : malaga;
    const double n = double(frames.size());
    // SENA: each frame to one half or the other at random (its odometry drifts by decimetres over
    // the loop: parts of it in time disagree where they meet, doc/fusion.md); Malaga: [0, k) and
    // [k - o, n), k and o at random.
    const CPose3D truth(uniform(-5, 5), uniform(-5, 5), 0, uniform(-30, 30) * M_PI / 180, 0, 0);
    std::size_t end_a = frames.size(), start_b = 0;
    std::vector<PosedFrame> first, second;
    if (on_sena) {
      for (const PosedFrame& f : frames) (uniform(0, 1) < 0.5 ? first : second).push_back(f);
    } else {
      end_a = std::size_t(n * uniform(0.4, 0.6));
      start_b = end_a - std::size_t(n * uniform(0.0, 0.1));
      first.assign(frames.begin(), frames.begin() + end_a);
      second.assign(frames.begin() + start_b, frames.end());
    }
    const auto a = buildPart(first, 0, first.size());
    const auto b = buildPart(second, 0, second.size(), truth);
    rtog::TMapRegistrationOptions o;
    // A guess within a few decimetres and degrees; the heading searched 10 degrees either side.
    o.guessX = truth.x() + normal(0.3), o.guessY = truth.y() + normal(0.3);
    o.guessYaw = truth.yaw() + normal(3.0) * M_PI / 180;
    o.headingSpanDeg = 20, o.headingStepDeg = 10;
    const rtog::TMapRegistration r = rtog::registerMaps(*a, *b, o);
    EXPECT_TRUE(r.converged) << "trial " << t << ": " << r.failure;
    const Eigen::Vector3d e = registrationError(r, truth);
    const Eigen::Matrix3d c = planarCov(r);
    const double d2 = mahalanobis2(r, truth);
    inside += d2 <= kTwoSigma3Dof;
    sum_d2 += d2;
    worst_t = std::max(worst_t, std::hypot(e.x(), e.y())), worst_yaw = std::max(worst_yaw, std::fabs(e.z()));
    std::printf("trial %2d %-6s %3zu + %3zu frames: error %6.3f %6.3f m %6.3f deg, sigma %.3f %.3f m %.3f deg, "
                "d2 %6.2f, goodness %.2f, rms %.3f m\n",
                t, on_sena ? "SENA" : "Malaga", first.size(), second.size(), e.x(), e.y(), e.z() * 180 / M_PI,
                std::sqrt(c(0, 0)), std::sqrt(c(1, 1)), std::sqrt(c(2, 2)) * 180 / M_PI, d2, r.goodness,
                r.rmsResidual);
  }
  std::printf("%d of %d errors within the 2-sigma ellipsoid (d2 <= %.2f), mean d2 %.2f (3 if calibrated); "
              "largest error %.3f m, %.3f deg\n",
              inside, kTrials, kTwoSigma3Dof, sum_d2 / kTrials, worst_t, worst_yaw * 180 / M_PI);
  EXPECT_GE(inside, (9 * kTrials + 9) / 10);
  // Registered, not only covered: within a few centimetres and a fraction of a degree.
  EXPECT_LT(worst_t, 0.15);
  EXPECT_LT(worst_yaw * 180 / M_PI, 1.0);
}
