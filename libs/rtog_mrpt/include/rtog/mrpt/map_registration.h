// Registration of two maps before fusion (doc/fusion.md): the pose of one map's frame in the
// other's, with its covariance, when it is not given. ICP (MRPT's CICP) on the occupied cells of
// a height band, started from several headings; the covariance is computed here from the
// matched cells' residuals (CICP's is a placeholder for maps that already agree, doc/fusion.md).
#pragma once

#include <cstddef>
#include <string>

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
  /// The width of the heading search [deg]: starts from guessYaw - span/2 up to (not including)
  /// guessYaw + span/2; 360 searches all headings, a narrower span trusts the guess. (Default: 360)
  double headingSpanDeg{360.0};
  /// The guess of the second map's frame in the first's (x, y [m], yaw [rad]). (Default: 0)
  double guessX{0.0}, guessY{0.0}, guessYaw{0.0};
  /// Matching distance ICP starts with [m], and ends with; 0 ends with 0.75 times the coarser
  /// map's resolution: a point is within 0.71 cells of its nearest lattice point, so two samplings
  /// of one wall on different lattices stay within it, while on one lattice a neighbouring cell
  /// (1 cell away) does not pair. Cells of the second map within endDistance of a cell of the
  /// first are the matched ones. (Default: 3, 0)
  double startDistance{3.0}, endDistance{0.0};
  /// Occupied cells used per map at most (taken evenly): ICP's cost. (Default: 20000)
  std::size_t maxPoints{20000};
  /// The least share of the second map's cells that must be matched at the result: below it the
  /// maps share too little for a registration. (Default: 0.25)
  double minGoodness{0.25};
};

struct TMapRegistration {
  /// false: no registration; `failure` says why, and `pose` must not be used.
  bool converged{false};
  std::string failure;
  /// The second map's frame in the first's, for fuse(); z, pitch and roll 0 and certain. Its
  /// x, y, yaw covariance is N sigma^2 H^-1 of doc/fusion.md ("Registration").
  mrpt::poses::CPose3DPDFGaussian pose;
  /// The fraction of the second map's cells in the band that have a cell of the first within
  /// endDistance at the result, of the best start.
  double goodness{0.0};
  std::size_t pointsA{0}, pointsB{0};  ///< occupied cells in the band, of each map
  std::size_t matched{0};              ///< of the second map's, those matched within endDistance
  std::size_t pairs{0};                ///< of the second map's, those paired within 1.5 cells
                                       ///< (the covariance's pairs)
  double rmsResidual{0.0};             ///< of the covariance's pairs (within 1.5 cells) [m]
};

/// Estimates the pose of `b`'s frame in `a`'s from their occupied cells in the band. Throws
/// std::invalid_argument for bad options and std::runtime_error if a map has fewer than 10
/// occupied cells in the band. Maps that share too little (goodness under minGoodness), and a
/// result whose covariance is not finite or not positive definite, are returned with
/// `converged` false and the reason.
TMapRegistration registerMaps(const CRTreeOccupancyGridMap& a, const CRTreeOccupancyGridMap& b,
                              const TMapRegistrationOptions& o = {});

/// fuse() with the registration's covariance blurred in (OccupancyMap::fuse over the sigma
/// points of `pose`, as insertObservation with a CPose3DPDFGaussian blurs a scan).
InsertStats fuseUncertain(CRTreeOccupancyGridMap& into, const CRTreeOccupancyGridMap& other,
                          const mrpt::poses::CPose3DPDFGaussian& pose);

}  // namespace rtog
