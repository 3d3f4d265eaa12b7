// Robot poses for the observations of a rawlog, by dead reckoning.
#pragma once

#include <cstddef>
#include <functional>

#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/serialization/CSerializable.h>

namespace rtog {

using OdometryVisit = std::function<void(const mrpt::obs::CObservation::Ptr&, const mrpt::poses::CPose3D&, std::size_t)>;

/// Calls visit(observation, robot_pose, entry_index) for every observation of `log`, in order,
/// with the robot pose integrated from the origin: odometry actions in the actions/sensory-frame
/// format, CObservationOdometry readings in the observation format (those are not visited). A
/// rawlog carries no better pose; use a simplemap for corrected poses.
void forEachOdometryObservation(const mrpt::obs::CRawlog& log, const OdometryVisit& visit);

/// The same walk over a rawlog's entries given one at a time, in the file's order (a log read as
/// a stream, never whole): each action collection moves the pose, each sensory frame's
/// observations and each observation are visited at it.
class OdometryWalk {
 public:
  void feed(const mrpt::serialization::CSerializable::Ptr& entry, std::size_t index, const OdometryVisit& visit);

 private:
  mrpt::poses::CPose2D odometry_;
};

}  // namespace rtog
