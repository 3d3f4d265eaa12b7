// Robot poses for the observations of a rawlog, by dead reckoning.
#pragma once

#include <cstddef>
#include <functional>

#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/poses/CPose3D.h>

namespace rtog {

/// Calls visit(observation, robot_pose, entry_index) for every observation of `log`, in order,
/// with the robot pose integrated from the origin: odometry actions in the actions/sensory-frame
/// format, CObservationOdometry readings in the observation format (those are not visited). A
/// rawlog carries no better pose; use a simplemap for corrected poses.
void forEachOdometryObservation(
    const mrpt::obs::CRawlog& log,
    const std::function<void(const mrpt::obs::CObservation::Ptr&, const mrpt::poses::CPose3D&, std::size_t)>& visit);

}  // namespace rtog
