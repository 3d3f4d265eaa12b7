// rtog::CRTreeOccupancyGridMap: observations inserted with an uncertain pose (poseUncertainty),
// the pose covariance blurred into the update through its sigma points (doc/pose-uncertainty.md).
#include <stdexcept>
#include <vector>

#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CSensoryFrame.h>

#include "rtog/core/pose_blur.hpp"
#include <mrpt/obs/CObservationRange.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

bool CRTreeOccupancyGridMap::insertObservation(const mrpt::obs::CObservation& obs,
                                               const mrpt::poses::CPose3DPDFGaussian& pose) {
  if (!insertionOptions.poseUncertainty) return insertObservation(obs, pose.mean);
  // A sonar reading already spreads over its cone: inserted at the mean (doc/sonar.md).
  if (dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) return insertObservation(obs, pose.mean);
  insertionOptions.validate();  // the mrpt_grid preset has no graded update
  Eigen::MatrixXd cov(6, 6);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) cov(r, c) = pose.cov(r, c);
  const std::vector<SigmaPoint> sigma = sigmaPoints(cov);  // throws for a matrix that is not a covariance
  if (sigma.size() == 1) return insertObservation(obs, pose.mean);  // a certain pose: the plain update
  if (!genericMapParams.enableObservationInsertion) return false;
  // MRPT's Gaussian pose is one over the six parameters (x, y, z, yaw, pitch, roll), added to the
  // mean's (CPose3DPDFGaussian::drawSingleSample): so are the sigma points.
  const mrpt::poses::CPose3D& m = pose.mean;
  std::vector<ObservationBeams> beams(sigma.size());
  for (std::size_t i = 0; i < sigma.size(); ++i) {
    const Eigen::VectorXd& o = sigma[i].offset;
    const mrpt::poses::CPose3D p(m.x() + o[0], m.y() + o[1], m.z() + o[2], m.yaw() + o[3], m.pitch() + o[4],
                                 m.roll() + o[5]);
    if (!extractBeams(obs, p, beams[i], true)) return false;
  }
  std::vector<WeightedScan> scans;
  for (std::size_t i = 0; i < sigma.size(); ++i)
    scans.push_back(WeightedScan{sigma[i].weight, beams[i].origin, beams[i].points.data(), beams[i].points.size(),
                                 beams[i].is_hit.data()});
  syncParams();
  lastInsertStats = map_.insertBlurred(scans, insertionOptions.toInsertParams());
  totalInsertStats += lastInsertStats;
  invalidRangesSkipped += beams[0].invalid;
  notifyMapChanged();
  publishEvent(mrpt::maps::mrptEventMetricMapInsert(this, &obs, pose.mean));
  return true;
}

bool CRTreeOccupancyGridMap::insertObservation(const mrpt::obs::CObservation& obs,
                                               const mrpt::poses::CPosePDFGaussian& pose) {
  return insertObservation(obs, mrpt::poses::CPose3DPDFGaussian(pose));
}

void CRTreeOccupancyGridMap::loadFromProbabilisticPosesAndObservations(const mrpt::maps::CSimpleMap& sm) {
  clear();
  for (const auto& pair : sm) {
    if (!pair.pose) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a simplemap frame has no pose");
    if (!pair.sf) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a simplemap frame has no observations");
    mrpt::poses::CPose3DPDFGaussian g;
    g.copyFrom(*pair.pose);  // a particle or mixture PDF as its mean and covariance
    for (const auto& obs : *pair.sf)
      if (obs) insertObservation(*obs, g);
  }
}

}  // namespace rtog
