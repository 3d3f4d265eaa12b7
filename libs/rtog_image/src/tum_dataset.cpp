#include "rtog/image/tum_dataset.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace rtog::image {

DepthSequence readTumSequence(const std::string& dir, const DepthIntrinsics& intrinsics) {
  const std::string path = dir + "/groundtruth_poses.txt";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  DepthSequence seq;
  seq.intrinsics = intrinsics;
  std::string line;
  for (int lineno = 1; std::getline(in, line); ++lineno) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string rgb, depth;
    double t[3], q[4];
    if (!(ls >> rgb >> depth >> t[0] >> t[1] >> t[2] >> q[0] >> q[1] >> q[2] >> q[3]))
      throw std::runtime_error(path + ":" + std::to_string(lineno) + ": expected 'rgb depth tx ty tz qx qy qz qw'");
    const Eigen::Quaterniond rot(q[3], q[0], q[1], q[2]);
    if (!(std::abs(rot.norm() - 1.0) < 1e-3))
      throw std::runtime_error(path + ":" + std::to_string(lineno) + ": quaternion is not normalized");
    DepthFrame f;
    f.depth_path = dir + "/" + depth;
    f.camera_to_world.linear() = rot.normalized().toRotationMatrix();
    f.camera_to_world.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    seq.frames.push_back(f);
  }
  if (seq.frames.empty()) throw std::runtime_error(path + ": no frames");
  return seq;
}

namespace {

/// `scale` pixel values per metre.
template <class Pixel>
void backProject(const cv::Mat& depth, const Eigen::Isometry3d& camera_to_world, const DepthIntrinsics& k,
                 double scale, int stride, WorldScan& scan) {
  scan.origin = camera_to_world.translation();
  scan.points.reserve(static_cast<std::size_t>(depth.rows / stride + 1) * (depth.cols / stride + 1));
  const Eigen::Matrix3f r = camera_to_world.linear().cast<float>();
  const Eigen::Vector3f t = camera_to_world.translation().cast<float>();
  for (int v = 0; v < depth.rows; v += stride) {
    const auto* row = depth.ptr<Pixel>(v);
    for (int u = 0; u < depth.cols; u += stride) {
      if (!(row[u] > 0) || !std::isfinite(double(row[u]))) {
        ++scan.pixels_without_depth;
        continue;
      }
      const double z = row[u] / scale;
      const Eigen::Vector3f pc(float((u - k.cx) * z / k.fx), float((v - k.cy) * z / k.fy), float(z));
      scan.points.push_back(r * pc + t);
    }
  }
}

}  // namespace

WorldScan depthScan(const cv::Mat& depth, const Eigen::Isometry3d& camera_to_world, const DepthIntrinsics& k,
                    int stride) {
  if (stride < 1) throw std::invalid_argument("depthScan: stride must be >= 1");
  WorldScan scan;
  if (depth.type() == CV_16UC1)
    backProject<std::uint16_t>(depth, camera_to_world, k, k.depth_scale, stride, scan);
  else if (depth.type() == CV_32FC1)
    backProject<float>(depth, camera_to_world, k, 1.0, stride, scan);
  else
    throw std::invalid_argument("depthScan: expected a 16-bit (depth_scale per metre) or 32-bit float (metres) "
                                "single-channel image");
  return scan;
}

WorldScan loadDepthScan(const DepthFrame& frame, const DepthIntrinsics& k, int stride) {
  if (stride < 1) throw std::invalid_argument("loadDepthScan: stride must be >= 1");
  const cv::Mat depth = cv::imread(frame.depth_path, cv::IMREAD_ANYDEPTH);
  if (depth.empty()) throw std::runtime_error("cannot read depth image " + frame.depth_path);
  if (depth.type() != CV_16UC1) throw std::runtime_error(frame.depth_path + ": expected a 16-bit single-channel PNG");
  return depthScan(depth, frame.camera_to_world, k, stride);
}

}  // namespace rtog::image
