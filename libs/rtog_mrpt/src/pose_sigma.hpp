// An uncertain MRPT pose (CPose3DPDFGaussian) as the sigma points the pose-blurred insertion
// mixes (rtog::sigmaPoints, doc/pose-uncertainty.md): the helper of
// CRTreeOccupancyGridMap::insertObservation(obs, CPose3DPDFGaussian).
#pragma once

#include <vector>

#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include "rtog/core/pose_blur.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::pose_sigma {

struct SigmaPose {
  double weight;
  mrpt::poses::CPose3D pose;
};

/// The sigma points of `pose`: one (the mean) for a zero covariance. MRPT's Gaussian pose is one
/// over the six parameters (x, y, z, yaw, pitch, roll), added to the mean's
/// (CPose3DPDFGaussian::drawSingleSample): so are the sigma points. Throws
/// std::invalid_argument for a matrix that is not a covariance.
std::vector<SigmaPose> sigmaPoses(const mrpt::poses::CPose3DPDFGaussian& pose);

/// Each sigma pose as the move (map frame) that carries the mean pose to it, pose * mean^-1, as
/// OccupancyMap::insertBlurred takes them with the beams extracted at the mean.
std::vector<PoseMove> poseMoves(const std::vector<SigmaPose>& sigma, const mrpt::poses::CPose3D& mean);

}  // namespace rtog::pose_sigma
