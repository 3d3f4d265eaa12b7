#include "rtog/mrpt/rawlog_poses.h"

#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>

namespace rtog {

void forEachOdometryObservation(
    const mrpt::obs::CRawlog& log,
    const std::function<void(const mrpt::obs::CObservation::Ptr&, const mrpt::poses::CPose3D&, std::size_t)>& visit) {
  mrpt::poses::CPose2D odometry;
  for (std::size_t i = 0; i < log.size(); ++i) {
    switch (log.getType(i)) {
      case mrpt::obs::CRawlog::etActionCollection:
        if (const auto mv = log.getAsAction(i)->getBestMovementEstimation())
          odometry = odometry + mv->poseChange->getMeanVal();
        break;
      case mrpt::obs::CRawlog::etSensoryFrame:
        for (const auto& obs : *log.getAsObservations(i)) visit(obs, mrpt::poses::CPose3D(odometry), i);
        break;
      case mrpt::obs::CRawlog::etObservation: {
        const auto obs = log.getAsObservation(i);
        if (const auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obs)) {
          odometry = odo->odometry;
        } else {
          visit(obs, mrpt::poses::CPose3D(odometry), i);
        }
        break;
      }
      default:
        break;
    }
  }
}

}  // namespace rtog
