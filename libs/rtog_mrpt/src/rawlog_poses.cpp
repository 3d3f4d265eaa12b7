#include "rtog/mrpt/rawlog_poses.h"

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>

namespace rtog {

void OdometryWalk::feed(const mrpt::serialization::CSerializable::Ptr& entry, std::size_t index,
                        const OdometryVisit& visit) {
  if (const auto acts = std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(entry)) {
    if (const auto mv = acts->getBestMovementEstimation()) odometry_ = odometry_ + mv->poseChange->getMeanVal();
  } else if (const auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(entry)) {
    for (const auto& obs : *sf) visit(obs, mrpt::poses::CPose3D(odometry_), index);
  } else if (const auto obs = std::dynamic_pointer_cast<mrpt::obs::CObservation>(entry)) {
    if (const auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obs))
      odometry_ = odo->odometry;
    else
      visit(obs, mrpt::poses::CPose3D(odometry_), index);
  }
}

void forEachOdometryObservation(const mrpt::obs::CRawlog& log, const OdometryVisit& visit) {
  OdometryWalk walk;
  for (std::size_t i = 0; i < log.size(); ++i) walk.feed(log.getAsGeneric(i), i, visit);
}

}  // namespace rtog
