// The covariance of a planar registration from its matched cells (doc/fusion.md, "Registration").
#pragma once

#include <cstddef>

#include <Eigen/Core>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPose2D.h>

namespace rtog::detail {

struct RegistrationFit {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  ///< of x, y [m] and yaw [rad]
  std::size_t matched = 0, tiles = 0;
  double goodness = 0.0;  ///< matched / points of b
  double rms = 0.0;       ///< of the covariance's pairs' residuals [m]
};

/// Pairs each point of `b`, moved by `pose`, with its nearest point of `a`; counts in `matched`
/// (and `goodness`) the pairs within `gate` [m], and returns from the pairs within `wide` [m] the
/// larger (in every direction) of a floor, N sigma^2 H^-1 with sigma^2 = the residuals' variance
/// per axis + q (the pairs' error counted as shared by all of them), and of the
/// cluster-robust sandwich H^-1 (G/(G-1) sum_t g_t g_t^T + q H) H^-1, where H = sum J^T J over the
/// pairs, g_t = sum J^T r over the pairs whose point of `a` lies in square tile t (G tiles), and
/// q [m^2] is the per-axis variance the two lattices' quantization adds to each pair. Tiles of
/// side `tile` [m], then twice that, ... while there are at least `min_tiles`; the result holds
/// each of those covariances (in every direction the largest variance). `tiles` is G at the
/// smallest side.
RegistrationFit registrationCovariance(const mrpt::maps::CSimplePointsMap& a, const mrpt::maps::CSimplePointsMap& b,
                                       const mrpt::poses::CPose2D& pose, double gate, double wide, double q,
                                       double tile, std::size_t min_tiles);

}  // namespace rtog::detail
