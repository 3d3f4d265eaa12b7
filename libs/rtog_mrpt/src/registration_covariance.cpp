// The covariance of a planar registration (registration_covariance.hpp). Why not CICP's own:
// CICP (MRPT 2.5.8, icpCovFiniteDifferences) inverts D D^T + 1e-6 I, where D holds the gradients
// of each pair's (kernelled) squared distance; those vanish where the pairs coincide, as the cells
// of two maps on one lattice do when the maps already agree (two chunks of one log, a copy), and
// the result is the placeholder 1e6 I. Where they do not vanish they scale with the residuals'
// size, not their spread between independent parts of the maps, and come out 6-12 times below the
// measured errors. Here the pose's spread is the least-squares estimator's: the residuals of one
// stretch of wall err together (the same poses saw it), so they enter by tile, and each pair also
// carries its two cell centres' quantization, which makes even an exact copy's covariance a
// positive definite one.
#include "registration_covariance.hpp"

#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace rtog::detail {

namespace {

struct Pair {
  double ax, ay;                ///< the point of a
  Eigen::Matrix<double, 2, 3> j;  ///< d(R b + t)/d(x, y, yaw)
  Eigen::Vector2d r;            ///< a - (R b + t)
};

/// sum over tiles of side `tile` of g g^T, g = sum J^T r of the tile's pairs, times G/(G-1).
Eigen::Matrix3d tileSpread(const std::vector<Pair>& pairs, double tile, std::size_t& tiles) {
  std::unordered_map<std::uint64_t, Eigen::Vector3d> by_tile;
  for (const Pair& p : pairs) {
    const auto cell = [&](double v) { return static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(v / tile))); };
    const std::uint64_t key = (static_cast<std::uint64_t>(cell(p.ax)) << 32) | cell(p.ay);
    by_tile.try_emplace(key, Eigen::Vector3d::Zero()).first->second += p.j.transpose() * p.r;
  }
  tiles = by_tile.size();
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const auto& [key, g] : by_tile) spread += g * g.transpose();
  return tiles > 1 ? Eigen::Matrix3d(spread * (double(tiles) / double(tiles - 1))) : spread;
}

/// The smallest covariance of the form L V max(I, Lambda) V^T L^T that holds both `c` (positive
/// definite, c = L L^T) and `d`: every direction keeps the larger of the two variances.
Eigen::Matrix3d upperBound(const Eigen::Matrix3d& c, const Eigen::Matrix3d& d) {
  const Eigen::Matrix3d l = Eigen::LLT<Eigen::Matrix3d>(c).matrixL();
  const Eigen::Matrix3d li = l.inverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> e(li * d * li.transpose());
  const Eigen::Vector3d grown = e.eigenvalues().cwiseMax(1.0);
  const Eigen::Matrix3d u = l * e.eigenvectors() * grown.asDiagonal() * e.eigenvectors().transpose() * l.transpose();
  return 0.5 * (u + u.transpose());
}

}  // namespace

RegistrationFit registrationCovariance(const mrpt::maps::CSimplePointsMap& a, const mrpt::maps::CSimplePointsMap& b,
                                       const mrpt::poses::CPose2D& pose, double gate, double wide, double q,
                                       double tile, std::size_t min_tiles) {
  RegistrationFit fit;
  const double c = std::cos(pose.phi()), s = std::sin(pose.phi());
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  std::vector<Pair> pairs;
  double sum_r2 = 0.0;
  const auto& xs = b.getPointsBufferRef_x();
  const auto& ys = b.getPointsBufferRef_y();
  for (std::size_t i = 0; i < xs.size(); ++i) {
    // The point of b turned (the yaw's lever arm) and then moved.
    const double rx = c * xs[i] - s * ys[i], ry = s * xs[i] + c * ys[i];
    const double px = rx + pose.x(), py = ry + pose.y();
    float ax = 0, ay = 0, d2 = 0;
    a.kdTreeClosestPoint2D(static_cast<float>(px), static_cast<float>(py), ax, ay, d2);
    const double dx = ax - px, dy = ay - py;
    if (dx * dx + dy * dy <= gate * gate) ++fit.matched;
    if (!(dx * dx + dy * dy <= wide * wide)) continue;
    Pair p{ax, ay, {}, Eigen::Vector2d(dx, dy)};
    p.j << 1, 0, -ry, 0, 1, rx;
    h += p.j.transpose() * p.j;
    sum_r2 += dx * dx + dy * dy;
    pairs.push_back(p);
  }
  fit.goodness = xs.empty() ? 0.0 : double(fit.matched) / double(xs.size());
  if (pairs.empty()) return fit;
  fit.rms = std::sqrt(sum_r2 / double(pairs.size()));
  const Eigen::LDLT<Eigen::Matrix3d> hinv(h);
  const auto sandwich = [&](const Eigen::Matrix3d& meat) {
    const Eigen::Matrix3d left = hinv.solve(meat);
    const Eigen::Matrix3d cov = hinv.solve(left.transpose());
    return Eigen::Matrix3d(0.5 * (cov + cov.transpose()));
  };
  // The floor: the pairs' error shared by the whole map. Both maps' cells were placed by one
  // chain of poses each, so their placement errors are not independent from cell to cell, and a
  // part common to all of them moves the optimum without showing in the residuals. Counted as
  // one pair's worth of information (N_eff = 1): per axis the residuals' variance plus the two
  // cell centres' quantization, the covariance N sigma^2 H^-1.
  const double sigma2 = sum_r2 / (2.0 * double(pairs.size())) + q;
  fit.cov = sandwich(double(pairs.size()) * sigma2 * h);
  if (!fit.cov.allFinite() || Eigen::LLT<Eigen::Matrix3d>(fit.cov).info() != Eigen::Success) return fit;
  // Tiles of doubling side while there are enough of them to tell a spread: where the maps
  // disagree over a large region (drift between the poses that saw it), its pairs err together
  // and only a tile that holds the region counts it at its weight.
  for (double side = tile;; side *= 2.0) {
    std::size_t tiles = 0;
    const Eigen::Matrix3d spread = tileSpread(pairs, side, tiles);
    if (side == tile) fit.tiles = tiles;
    if (tiles < min_tiles) break;
    fit.cov = upperBound(fit.cov, sandwich(spread + q * h));
  }
  return fit;
}

}  // namespace rtog::detail
