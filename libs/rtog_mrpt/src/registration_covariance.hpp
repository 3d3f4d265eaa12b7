// The covariance of a planar registration from its paired cells (doc/fusion.md, "Registration").
#pragma once

#include <cstddef>

#include <Eigen/Core>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/poses/CPose2D.h>

namespace rtog::detail {

struct RegistrationFit {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();  ///< of x, y [m] and yaw [rad]
  std::size_t matched = 0;  ///< points of b paired within `gate`
  std::size_t pairs = 0;    ///< points of b paired within `wide`: the covariance's
  double goodness = 0.0;    ///< matched / points of b
  double rms = 0.0;         ///< of the covariance's pairs' residuals [m]
};

/// Pairs each point of `b`, moved by `pose`, with its nearest point of `a`; counts the pairs
/// within `gate` [m] as matched, and from the N pairs within `wide` [m] returns N sigma^2 H^-1,
/// H = sum J^T J (J = d(R b + t)/d(x, y, yaw)), sigma^2 = the residuals' variance per axis + q
/// (q [m^2]: the per-axis variance the two lattices' quantization adds to a pair).
RegistrationFit registrationCovariance(const mrpt::maps::CSimplePointsMap& a, const mrpt::maps::CSimplePointsMap& b,
                                       const mrpt::poses::CPose2D& pose, double gate, double wide, double q);

}  // namespace rtog::detail
