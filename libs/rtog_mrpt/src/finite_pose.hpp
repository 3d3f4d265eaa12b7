// Whether every component of a pose is finite, and the score of an observation from one that is not.
#pragma once

#include <cmath>

#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/poses/CPose3D.h>

namespace rtog::detail {

/// The log-likelihood of an observation from a non-finite pose: impossible, below any real score
/// (a scan's sum is bounded by beams * log(LF_zRandom/LF_maxRange)), yet finite, because MRPT's
/// particle filters assert finite log-likelihoods and subtract the maximum before exp().
constexpr double kImpossibleLogLik = -1e30;

inline bool finitePose(const mrpt::poses::CPose3D& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()) && std::isfinite(p.yaw()) &&
         std::isfinite(p.pitch()) && std::isfinite(p.roll());
}

/// The robot pose and the observation's sensor pose on it both finite, angles included (a NaN
/// angle makes every end point NaN: no beam would be scored, and an empty sum is the best score).
/// Every reading of a CObservationRange has its own sensor pose (getSensorPose gives the first
/// one's): all are checked, or a reading with a NaN pose would drop out of the score.
inline bool finitePoses(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robot) {
  if (!finitePose(robot)) return false;
  if (const auto* range = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) {
    for (const auto& d : range->sensedData)
      for (int i = 0; i < 6; ++i)
        if (!std::isfinite(d.sensorPose[i])) return false;
    return true;
  }
  mrpt::poses::CPose3D sensor;
  obs.getSensorPose(sensor);
  return finitePose(sensor);
}

}  // namespace rtog::detail
