// Pose uncertainty blurred into an update (seed: M_G = M_G (+) (V_R (-) R)). A scan taken from an
// uncertain pose is entered once, as the mixture over a deterministic sample set of poses of the
// per-cell occupancy probabilities the sensor model gives from each: the local view convolved
// with the pose distribution (doc/pose-uncertainty.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

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

/// One pose of OccupancyMap::insertBlurred() given as a move of the scan taken at the mean pose:
/// the rigid motion (map frame) that carries the mean pose to this pose, x -> move * x (for MRPT
/// poses, pose_i * mean^-1), with the pose's weight.
struct PoseMove {
  double weight = 1.0;
  Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
};

/// The move of a planar pose error about a sensor at `about`: shifted by (dx, dy), turned by dyaw
/// about the vertical through `about`.
inline PoseMove planarMove(double weight, const Eigen::Vector3d& about, double dx, double dy, double dyaw) {
  PoseMove m;
  m.weight = weight;
  m.move = Eigen::Translation3d(about + Eigen::Vector3d(dx, dy, 0.0)) * Eigen::AngleAxisd(dyaw, Eigen::Vector3d::UnitZ()) *
           Eigen::Translation3d(-about);
  return m;
}

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
