// Registration of two maps before fusion (doc/fusion.md): the pose of one map's frame in the
// other's, with its covariance, when it is not given. ICP (MRPT's CICP) on the occupied cells of
// a height band, started from several headings.
#pragma once

#include <cstddef>

#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

struct TMapRegistrationOptions {
  /// Height band [m]: the occupied cells whose centres lie in it are matched (walls, not floors).
  /// (Default: -1000, 1000)
  float minZ{-1000.0f}, maxZ{1000.0f};
  /// Headings the search starts from, this far apart [deg], each from a zero translation plus
  /// the guess: a wrong heading is where ICP fails, a few metres it recovers. (Default: 10)
  double headingStepDeg{10.0};
  /// The guess of the second map's frame in the first's (x, y [m], yaw [rad]). (Default: 0)
  double guessX{0.0}, guessY{0.0}, guessYaw{0.0};
  /// Matching distance ICP starts with [m], and ends with. (Default: 3, 0.05)
  double startDistance{3.0}, endDistance{0.05};
  /// Occupied cells used per map at most (taken evenly): ICP's cost. (Default: 20000)
  std::size_t maxPoints{20000};
};

struct TMapRegistration {
  /// The second map's frame in the first's, for fuse(); z, pitch and roll 0 and certain.
  mrpt::poses::CPose3DPDFGaussian pose;
  /// The fraction of the second map's matched cells that found a partner within endDistance
  /// (ICP's goodness), of the best start.
  double goodness{0.0};
  std::size_t pointsA{0}, pointsB{0};  ///< occupied cells matched, of each map
};

/// Estimates the pose of `b`'s frame in `a`'s from their occupied cells in the band. Throws
/// std::invalid_argument for bad options and std::runtime_error if a map has fewer than 10
/// occupied cells in the band.
TMapRegistration registerMaps(const CRTreeOccupancyGridMap& a, const CRTreeOccupancyGridMap& b,
                              const TMapRegistrationOptions& o = {});

/// fuse() with the registration's covariance blurred in (OccupancyMap::fuse over the sigma
/// points of `pose`, as insertObservation with a CPose3DPDFGaussian blurs a scan).
InsertStats fuseUncertain(CRTreeOccupancyGridMap& into, const CRTreeOccupancyGridMap& other,
                          const mrpt::poses::CPose3DPDFGaussian& pose);

}  // namespace rtog
