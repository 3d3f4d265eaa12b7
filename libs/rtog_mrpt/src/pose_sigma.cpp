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

std::vector<PoseMove> poseMoves(const std::vector<SigmaPose>& sigma, const mrpt::poses::CPose3D& mean) {
  const auto isometry = [](const mrpt::poses::CPose3D& p) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) t.linear()(r, c) = p.getRotationMatrix()(r, c);
      t.translation()[r] = p.m_coords[static_cast<std::size_t>(r)];
    }
    return t;
  };
  const Eigen::Isometry3d back = isometry(mean).inverse();
  std::vector<PoseMove> moves;
  for (const SigmaPose& s : sigma) moves.push_back(PoseMove{s.weight, isometry(s.pose) * back});
  return moves;
}

}  // namespace rtog::pose_sigma
