#include "pose_sigma.hpp"

namespace rtog::pose_sigma {

std::vector<SigmaPose> sigmaPoses(const mrpt::poses::CPose3DPDFGaussian& pose) {
  Eigen::MatrixXd cov(6, 6);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) cov(r, c) = pose.cov(r, c);
  const std::vector<SigmaPoint> sigma = sigmaPoints(cov);  // throws for a matrix that is not a covariance
  const mrpt::poses::CPose3D& m = pose.mean;
  std::vector<SigmaPose> out;
  out.reserve(sigma.size());
  for (const SigmaPoint& s : sigma) {
    const Eigen::VectorXd& o = s.offset;
    out.push_back(SigmaPose{s.weight, mrpt::poses::CPose3D(m.x() + o[0], m.y() + o[1], m.z() + o[2], m.yaw() + o[3],
                                                           m.pitch() + o[4], m.roll() + o[5])});
  }
  return out;
}

std::vector<WeightedScan> weightedScans(const std::vector<SigmaPose>& sigma, const std::vector<ObservationBeams>& beams) {
  std::vector<WeightedScan> scans;
  for (std::size_t i = 0; i < sigma.size(); ++i)
    scans.push_back(WeightedScan{sigma[i].weight, beams[i].origin, beams[i].points.data(), beams[i].points.size(),
                                 beams[i].is_hit.data()});
  return scans;
}

}  // namespace rtog::pose_sigma
