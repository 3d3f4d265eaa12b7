// Pose uncertainty blurred into an update (seed: M_G = M_G (+) (V_R (-) R)). A scan taken from an
// uncertain pose is entered once, as the mixture over a deterministic sample set of poses of the
// per-cell occupancy probabilities the sensor model gives from each: the local view convolved
// with the pose distribution (doc/pose-uncertainty.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rtog {

/// One scan of OccupancyMap::insertBlurred(): the beams as seen from one pose of the sample set
/// (map frame, as insertPointCloud() takes them), with that pose's weight.
struct WeightedScan {
  double weight = 1.0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  const Eigen::Vector3f* points = nullptr;
  std::size_t count = 0;
  const std::uint8_t* is_hit = nullptr;  ///< optional, as in insertPointCloud()
};

/// A sample of a zero-mean Gaussian: an offset to add to the mean and its weight.
struct SigmaPoint {
  Eigen::VectorXd offset;
  double weight = 0.0;
};

/// The symmetric sigma-point set of a zero-mean Gaussian of covariance `cov` (n x n, symmetric,
/// positive semi-definite): for each of its m eigen-directions of positive variance lambda, the
/// two points +-sqrt(m * lambda) along it, each of weight 1 / (2m). The set has the Gaussian's
/// mean and covariance exactly, and all its weights are positive, so a mixture over it is a
/// probability. A zero covariance gives the one point 0 of weight 1. Throws
/// std::invalid_argument for a matrix that is not square, not finite, not symmetric or has a
/// negative eigenvalue.
std::vector<SigmaPoint> sigmaPoints(const Eigen::MatrixXd& cov);

}  // namespace rtog
