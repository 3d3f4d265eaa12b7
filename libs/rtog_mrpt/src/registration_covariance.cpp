// The covariance of a planar registration (registration_covariance.hpp). Why not CICP's own:
// CICP (MRPT 2.5.8, icpCovFiniteDifferences) inverts D D^T + 1e-6 I, where D holds the gradients
// of each pair's (kernelled) squared distance; those vanish where the pairs coincide, as the cells
// of two maps on one lattice do when the maps already agree (two chunks of one log, a copy), and
// the result is the placeholder 1e6 I. Where they do not vanish, it treats the pairs as
// independent measurements and comes out 6-12 times below the measured errors.
//
// Here the pairs' errors are not taken as independent: both maps' cells were placed by chains of
// poses whose errors are common to many cells, and the part common to all of them moves the
// optimum without showing in the residuals. The pose is taken to be known as well as one pair
// (the sandwich H^-1 (sum_i J_i^T e)(sum_i J_i^T e)^T H^-1 with one error e shared by all pairs,
// the largest a cluster-robust estimate over any grouping of the pairs can give), with the pair's
// error variance per axis that of the residuals plus the two cell centres' quantization.
#include "registration_covariance.hpp"

#include <cmath>

#include <Eigen/Cholesky>

namespace rtog::detail {

RegistrationFit registrationCovariance(const mrpt::maps::CSimplePointsMap& a, const mrpt::maps::CSimplePointsMap& b,
                                       const mrpt::poses::CPose2D& pose, double gate, double wide, double q) {
  RegistrationFit fit;
  const double c = std::cos(pose.phi()), s = std::sin(pose.phi());
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  double sum_r2 = 0.0;
  const auto& xs = b.getPointsBufferRef_x();
  const auto& ys = b.getPointsBufferRef_y();
  for (std::size_t i = 0; i < xs.size(); ++i) {
    // The point of b turned (the yaw's lever arm) and then moved.
    const double rx = c * xs[i] - s * ys[i], ry = s * xs[i] + c * ys[i];
    const double px = rx + pose.x(), py = ry + pose.y();
    float ax = 0, ay = 0, d2 = 0;
    a.kdTreeClosestPoint2D(static_cast<float>(px), static_cast<float>(py), ax, ay, d2);
    const double dx = ax - px, dy = ay - py, r2 = dx * dx + dy * dy;
    if (r2 <= gate * gate) ++fit.matched;
    if (!(r2 <= wide * wide)) continue;
    // d(R b + t)/d(x, y, yaw).
    Eigen::Matrix<double, 2, 3> j;
    j << 1, 0, -ry, 0, 1, rx;
    h += j.transpose() * j;
    sum_r2 += r2;
    ++fit.pairs;
  }
  fit.goodness = xs.empty() ? 0.0 : double(fit.matched) / double(xs.size());
  if (fit.pairs == 0) return fit;
  fit.rms = std::sqrt(sum_r2 / double(fit.pairs));
  const double sigma2 = sum_r2 / (2.0 * double(fit.pairs)) + q;
  // N sigma^2 H^-1: H / N is one pair's information.
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(h);
  fit.cov = ldlt.solve(Eigen::Matrix3d::Identity()) * (double(fit.pairs) * sigma2);
  fit.cov = 0.5 * (fit.cov + fit.cov.transpose());
  return fit;
}

}  // namespace rtog::detail
