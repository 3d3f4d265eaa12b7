// Reader for TUM RGB-D style depth sequences: 16-bit depth PNGs plus ground-truth poses.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core/mat.hpp>

namespace rtog::image {

/// Pinhole depth camera. Defaults are the TUM freiburg2 Kinect.
struct DepthIntrinsics {
  double fx = 520.9;          ///< (Default: 520.9)
  double fy = 521.0;          ///< (Default: 521.0)
  double cx = 325.1;          ///< (Default: 325.1)
  double cy = 249.7;          ///< (Default: 249.7)
  double depth_scale = 5000;  ///< pixel value per metre. (Default: 5000)
};

struct DepthFrame {
  std::string depth_path;
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();  ///< optical frame pose
};

struct DepthSequence {
  std::vector<DepthFrame> frames;
  DepthIntrinsics intrinsics;
};

/// A scan in the world frame: sensor origin and end points of the valid pixels.
struct WorldScan {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3f> points;
  std::size_t pixels_without_depth = 0;
};

/// Reads `dir/groundtruth_poses.txt` (lines `rgb depth tx ty tz qx qy qz qw`, '#' comments).
/// Throws std::runtime_error with the file and line on malformed input.
DepthSequence readTumSequence(const std::string& dir, const DepthIntrinsics& intrinsics = {});

/// Loads one depth PNG and back-projects every `stride`-th pixel in each direction into the
/// world frame. Throws std::runtime_error if the image is missing or not 16-bit single channel.
WorldScan loadDepthScan(const DepthFrame& frame, const DepthIntrinsics& intrinsics, int stride = 1);

/// The same from a depth image in memory: CV_16UC1 (pixel values, intrinsics.depth_scale per
/// metre) or CV_32FC1 (metres); a zero or non-finite pixel has no depth. Throws
/// std::invalid_argument for another type or stride < 1.
WorldScan depthScan(const cv::Mat& depth, const Eigen::Isometry3d& camera_to_world, const DepthIntrinsics& intrinsics,
                    int stride = 1);

}  // namespace rtog::image
