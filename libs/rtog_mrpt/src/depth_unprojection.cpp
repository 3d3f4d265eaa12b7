#include "depth_unprojection.hpp"

#include <limits>
#include <stdexcept>
#include <string>

#include <mrpt/math/TPoint3D.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace rtog::detail {

void unprojectDecimated(const mrpt::obs::CObservation3DRangeScan& depth, std::size_t decimation,
                        std::vector<Eigen::Vector3f>& pts, std::size_t& invalid) {
  const std::string what = "rtog::CRTreeOccupancyGridMap: CObservation3DRangeScan ";
  if (decimation < 2) throw std::invalid_argument(what + "decimated unprojection needs a decimation of 2 or more");
  const auto& image = depth.rangeImage;
  const std::size_t W = static_cast<std::size_t>(image.cols()), H = static_cast<std::size_t>(image.rows());
  const auto& cam = depth.cameraParams;
  if (W != cam.ncols || H != cam.nrows)
    throw std::invalid_argument(what + "range image " + std::to_string(W) + " x " + std::to_string(H) +
                                " differs from its camera model's " + std::to_string(cam.ncols) + " x " +
                                std::to_string(cam.nrows));
  if (W == 0 || H == 0 || W % decimation != 0 || H % decimation != 0)
    throw std::invalid_argument(what + "range image " + std::to_string(W) + " x " + std::to_string(H) +
                                " is not a multiple of decimation_3d_range " + std::to_string(decimation));
  const std::size_t D = decimation, Wd = W / D, Hd = H / D;
  // Per block, as MRPT's do_project_3d_pointcloud: the least range above 0 (range x units in
  // float), at the block's centre pixel.
  std::vector<float> nearest;
  std::vector<cv::Vec2f> centres;
  nearest.reserve(Wd * Hd);
  centres.reserve(Wd * Hd);
  for (std::size_t rd = 0; rd < Hd; ++rd)
    for (std::size_t cd = 0; cd < Wd; ++cd) {
      float least = std::numeric_limits<float>::max();
      bool valid = false;
      for (std::size_t rb = 0; rb < D; ++rb)
        for (std::size_t cb = 0; cb < D; ++cb) {
          const float d = image.coeff(int(rd * D + rb), int(cd * D + cb)) * depth.rangeUnits;
          if (d > 0.0f) {
            valid = true;
            if (d < least) least = d;
          }
        }
      if (!valid) {
        ++invalid;
        continue;
      }
      nearest.push_back(least);
      centres.emplace_back(static_cast<float>(cd * D + D / 2), static_cast<float>(rd * D + D / 2));
    }
  if (centres.empty()) return;
  // The rays of those pixels as MRPT's table has them: undistorted, (1, -u, -v).
  cv::Mat intrinsics(3, 3, CV_64F);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) intrinsics.at<double>(i, j) = cam.intrinsicParams(i, j);
  const cv::Mat distortion(1, static_cast<int>(cam.dist.size()), CV_64F, const_cast<double*>(cam.dist.data()));
  const cv::Mat in(1, static_cast<int>(centres.size()), CV_32FC2, centres.data());
  cv::Mat out;
  cv::undistortPoints(in, out, intrinsics, distortion);
  pts.reserve(pts.size() + centres.size());
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const cv::Vec2f& p = out.at<cv::Vec2f>(static_cast<int>(i));
    mrpt::math::TPoint3Df v(1.0f, -p[0], -p[1]);
    if (!depth.range_is_depth) v *= 1.0f / v.norm();
    const float d = nearest[i];
    const Eigen::Vector3f q(v.x * d, v.y * d, v.z * d);
    if (!q.allFinite()) {  // a camera model with NaN or infinite terms
      ++invalid;
      continue;
    }
    pts.push_back(q);
  }
}

}  // namespace rtog::detail
