// rtog.Map's insertions: point clouds, depth images, 2D range scans and sonar/IR readings, each
// with the map's options (preset, sensor model, pose uncertainty), NumPy arrays in.
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRange.h>
#include <opencv2/core/mat.hpp>

#include "py_map.hpp"
#include "rtog/image/tum_dataset.hpp"

namespace rtog::python {
namespace {

/// MRPT's insertion with or without a covariance; the figures of what it did.
InsertStats insertObservation(CRTreeOccupancyGridMap& map, const mrpt::obs::CObservation& obs,
                              const mrpt::poses::CPose3DPDFGaussian& pdf, bool uncertain) {
  map.lastInsertStats = InsertStats{};
  const bool taken = uncertain ? map.insertObservation(obs, pdf)
                               : map.insertObservation(obs, std::optional<const mrpt::poses::CPose3D>(pdf.mean));
  if (!taken) throw std::runtime_error("the map did not take the observation (enableObservationInsertion off?)");
  return map.lastInsertStats;
}

void requireBlurOption(const CRTreeOccupancyGridMap& map, const pyb::object& cov) {
  if (!cov.is_none() && !map.insertionOptions.poseUncertainty)
    throw pyb::value_error("pose_cov given, but the map was made with poseUncertainty off (Map(..., poseUncertainty='on'))");
}

/// Points given in the map frame from `origin`: the core's call with the map's options (what
/// `rtog build` makes of a depth frame), or, with a pose covariance or in a 3D section of the
/// mrpt_grid preset, a point cloud observed at `origin`, through the MRPT map.
InsertStats insertWorldPoints(CRTreeOccupancyGridMap& map, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                              std::size_t n, const std::uint8_t* is_hit,
                              const mrpt::poses::CPose3DPDFGaussian* pose_pdf) {
  if (!pose_pdf && !map.gridFrame3D().defined) {
    // The core's call, as `rtog build` feeds it a depth frame.
    map.lastInsertStats = map.map().insertPointCloud(origin, points, n, map.insertionOptions.toInsertParams(), is_hit);
    map.totalInsertStats += map.lastInsertStats;
    map.notifyMapChanged();
    return map.lastInsertStats;
  }
  if (is_hit) throw std::invalid_argument("is_hit: a point cloud with a pose covariance or in a 3D grid section has every beam returned");
  // A point cloud observed from `origin`, through the MRPT map (pose blur, COccupancyGridMap3D's rule).
  auto obs = mrpt::obs::CObservationPointCloud::Create();
  auto pts = mrpt::maps::CSimplePointsMap::Create();
  pts->reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p = points[i] - origin.cast<float>();
    pts->insertPointFast(p.x(), p.y(), p.z());
  }
  obs->pointcloud = pts;
  mrpt::poses::CPose3DPDFGaussian pdf;
  if (pose_pdf) pdf = *pose_pdf;
  pdf.mean = mrpt::poses::CPose3D(origin.x(), origin.y(), origin.z(), 0, 0, 0);
  return insertObservation(map, *obs, pdf, pose_pdf != nullptr);
}

}  // namespace

void bindInsert(pyb::module_& m) {
  auto cls = pyb::class_<PyMap, std::shared_ptr<PyMap>>(m.attr("Map"));
  cls.def(
      "insert_point_cloud",
      [](PyMap& self, const FloatArray& points, const DoubleArray& origin, const pyb::object& is_hit,
         const pyb::object& pose_cov) {
        const std::size_t n = rowsOf(points, 3, "points");
        const Eigen::Vector3d o = point3(origin, "origin");
        std::optional<ByteArray> hit;
        if (!is_hit.is_none()) {
          hit = ByteArray::ensure(is_hit);
          if (!*hit || hit->size() != static_cast<pyb::ssize_t>(n)) throw pyb::value_error("is_hit: expected N flags");
        }
        requireBlurOption(*self.map, pose_cov);
        const auto pdf = mrptPosePdf(mrpt::poses::CPose3D(o.x(), o.y(), o.z(), 0, 0, 0), pose_cov);
        const auto* p = reinterpret_cast<const Eigen::Vector3f*>(points.data());
        const std::uint8_t* h = hit ? hit->data() : nullptr;
        const InsertStats s = self.write([&](CRTreeOccupancyGridMap& map) {
          return insertWorldPoints(map, o, p, n, h, pose_cov.is_none() ? nullptr : &pdf);
        });
        return statsDict(s);
      },
      pyb::arg("points"), pyb::arg("origin"), pyb::arg("is_hit") = pyb::none(), pyb::arg("pose_cov") = pyb::none(),
      R"doc(Integrates one scan: a beam from `origin` (3,) to each point of `points` (N, 3), map frame,
metres. float32 C-ordered points are read in place. `is_hit` (N,) flags returned beams; a 0 clears
space up to its point and marks nothing occupied. `pose_cov` (3x3 over x, y, yaw or 6x6 over
x, y, z, yaw, pitch, roll) blurs the scan by the sensor pose's uncertainty (needs
poseUncertainty='on'). Returns the insertion's figures (a dict: rays_hit, cells_free, ...).)doc");

  cls.def(
      "insert_depth_image",
      [](PyMap& self, const pyb::array& depth, const DoubleArray& pose, double fx, double fy, double cx, double cy,
         double depth_scale, int stride, const pyb::object& pose_cov) {
        if (depth.ndim() != 2) throw pyb::value_error("depth: expected an (H, W) image");
        cv::Mat image;
        pyb::array held;
        if (pyb::isinstance<pyb::array_t<std::uint16_t>>(depth)) {
          held = pyb::array_t<std::uint16_t, pyb::array::c_style | pyb::array::forcecast>::ensure(depth);
          image = cv::Mat(int(depth.shape(0)), int(depth.shape(1)), CV_16UC1, const_cast<void*>(held.data()));
        } else {
          if (depth.dtype().kind() != 'f')
            throw pyb::value_error("depth: expected uint16 (depth_scale per metre) or float (metres) pixels");
          held = FloatArray::ensure(depth);
          image = cv::Mat(int(depth.shape(0)), int(depth.shape(1)), CV_32FC1, const_cast<void*>(held.data()));
        }
        const Eigen::Isometry3d camera = isometry(pose, "pose");
        image::DepthIntrinsics k;
        k.fx = fx, k.fy = fy, k.cx = cx, k.cy = cy, k.depth_scale = depth_scale;
        requireBlurOption(*self.map, pose_cov);
        mrpt::poses::CPose3DPDFGaussian pdf = mrptPosePdf(mrpt::poses::CPose3D(), pose_cov);
        const InsertStats s = self.write([&](CRTreeOccupancyGridMap& map) {
          const image::WorldScan scan = image::depthScan(image, camera, k, stride);
          map.invalidRangesSkipped += scan.pixels_without_depth;
          return insertWorldPoints(map, scan.origin, scan.points.data(), scan.points.size(), nullptr,
                                   pose_cov.is_none() ? nullptr : &pdf);
        });
        return statsDict(s);
      },
      pyb::arg("depth"), pyb::arg("pose"), pyb::arg("fx") = 520.9, pyb::arg("fy") = 521.0, pyb::arg("cx") = 325.1,
      pyb::arg("cy") = 249.7, pyb::arg("depth_scale") = 5000.0, pyb::arg("stride") = 1, pyb::arg("pose_cov") = pyb::none(),
      R"doc(Integrates a depth image (H, W): uint16 pixels (depth_scale per metre, TUM/Kinect) or float
metres; 0 or non-finite is no depth. `pose` is the 4x4 camera-to-map transform of the optical frame
(z forward, x right, y down); fx, fy, cx, cy the pinhole intrinsics (defaults: TUM freiburg2); every
`stride`-th pixel in each direction. The same points and call as `rtog build --tum`.)doc");

  cls.def(
      "insert_scan_2d",
      [](PyMap& self, const FloatArray& ranges, const DoubleArray& pose, double aperture, double max_range,
         const pyb::object& valid, bool right_to_left, const pyb::object& sensor_pose, const pyb::object& pose_cov) {
        if (ranges.ndim() != 1) throw pyb::value_error("ranges: expected a 1-D array");
        const std::size_t n = static_cast<std::size_t>(ranges.shape(0));
        std::optional<ByteArray> ok;
        if (!valid.is_none()) {
          ok = ByteArray::ensure(valid);
          if (!*ok || ok->size() != static_cast<pyb::ssize_t>(n)) throw pyb::value_error("valid: expected one flag per range");
        }
        if (!(aperture > 0.0 && aperture <= 2.0 * M_PI)) throw pyb::value_error("aperture must lie in (0, 2 pi]");
        if (!(max_range > 0.0 && std::isfinite(max_range))) throw pyb::value_error("max_range must be positive and finite");
        mrpt::obs::CObservation2DRangeScan scan;
        scan.resizeScan(n);
        scan.aperture = float(aperture);
        scan.maxRange = float(max_range);
        scan.rightToLeft = right_to_left;
        if (!sensor_pose.is_none()) scan.sensorPose = mrptPose(DoubleArray::ensure(sensor_pose), "sensor_pose");
        const float* r = ranges.data();
        for (std::size_t i = 0; i < n; ++i) {
          const bool finite = std::isfinite(r[i]);
          scan.setScanRange(i, finite ? r[i] : 0.0f);
          scan.setScanRangeValidity(i, finite && (ok ? ok->data()[i] != 0 : (r[i] > 0.0f && r[i] < max_range)));
        }
        requireBlurOption(*self.map, pose_cov);
        const auto pdf = mrptPosePdf(mrptPose(pose, "pose"), pose_cov);
        const InsertStats s = self.write(
            [&](CRTreeOccupancyGridMap& map) { return insertObservation(map, scan, pdf, !pose_cov.is_none()); });
        return statsDict(s);
      },
      pyb::arg("ranges"), pyb::arg("pose"), pyb::arg("aperture") = M_PI, pyb::arg("max_range") = 80.0,
      pyb::arg("valid") = pyb::none(), pyb::arg("right_to_left") = true, pyb::arg("sensor_pose") = pyb::none(),
      pyb::arg("pose_cov") = pyb::none(),
      R"doc(Integrates a 2D range scan as MRPT's CObservation2DRangeScan: `ranges` (N,) [m] spread
evenly over `aperture` centred on the sensor's x axis, counter-clockwise if right_to_left; taken
from robot `pose` ((x, y, yaw), (x, y, z, yaw, pitch, roll) or 4x4) with the sensor at
`sensor_pose` on the robot. `valid` flags the ranges (default: finite, > 0 and < max_range). In the
mrpt_grid preset the cells are COccupancyGridMap2D's; `pose_cov` blurs by the pose's uncertainty.)doc");

  cls.def(
      "insert_range_readings",
      [](PyMap& self, const FloatArray& ranges, const DoubleArray& sensor_poses, const DoubleArray& pose,
         double aperture, double min_range, double max_range, const pyb::object& pose_cov) {
        if (ranges.ndim() != 1) throw pyb::value_error("ranges: expected a 1-D array");
        const std::size_t n = static_cast<std::size_t>(ranges.shape(0));
        if (rowsOf(sensor_poses, 6, "sensor_poses") != n) throw pyb::value_error("sensor_poses: expected one (x, y, z, yaw, pitch, roll) per range");
        mrpt::obs::CObservationRange obs;
        obs.minSensorDistance = float(min_range);
        obs.maxSensorDistance = float(max_range);
        obs.sensorConeApperture = float(aperture);
        const double* sp = sensor_poses.data();
        for (std::size_t i = 0; i < n; ++i) {
          mrpt::obs::CObservationRange::TMeasurement meas;
          meas.sensorID = static_cast<uint16_t>(i);
          meas.sensorPose = mrpt::math::TPose3D(sp[6 * i], sp[6 * i + 1], sp[6 * i + 2], sp[6 * i + 3], sp[6 * i + 4], sp[6 * i + 5]);
          meas.sensedDistance = ranges.data()[i];
          obs.sensedData.push_back(meas);
        }
        requireBlurOption(*self.map, pose_cov);
        const auto pdf = mrptPosePdf(mrptPose(pose, "pose"), pose_cov);
        const InsertStats s = self.write(
            [&](CRTreeOccupancyGridMap& map) { return insertObservation(map, obs, pdf, !pose_cov.is_none()); });
        return statsDict(s);
      },
      pyb::arg("ranges"), pyb::arg("sensor_poses"), pyb::arg("pose"), pyb::arg("aperture") = 20.0 * M_PI / 180.0,
      pyb::arg("min_range") = 0.0, pyb::arg("max_range") = 5.0, pyb::arg("pose_cov") = pyb::none(),
      R"doc(Integrates sonar / IR readings (MRPT's CObservationRange): one range per sensor, each
sensor at its row of `sensor_poses` (N, 6: x, y, z, yaw, pitch, roll on the robot), a cone of
`aperture` radians, robot at `pose`. The cone weighting is the map's sonarConeWeighting.)doc");
}

}  // namespace rtog::python
