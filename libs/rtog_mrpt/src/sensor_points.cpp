#include "sensor_points.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include "fingerprint.hpp"

namespace rtog::detail {

void SensorPoints::setSensor(const mrpt::poses::CPose3D& sensor) {
  R_ = sensor.getRotationMatrix();
  t_[0] = sensor.x(), t_[1] = sensor.y(), t_[2] = sensor.z();
  origin = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
}

std::size_t SensorPoints::read(std::size_t first, std::size_t m, Eigen::Vector3f* out, float* ranges,
                               std::size_t& dropped) const {
  const auto& R = R_;
  std::size_t kept = 0;
  for (std::size_t j = first; j < first + m; ++j) {
    const std::size_t i = j * dec * stride;
    const float fx = x[i], fy = y[i], fz = z[i];
    if (!std::isfinite(fx) || !std::isfinite(fy) || !std::isfinite(fz) ||
        (zero_is_invalid && fx == 0 && fy == 0 && fz == 0)) {
      ++dropped;
      continue;
    }
    const double lx = fx, ly = fy, lz = fz;
    out[kept] = Eigen::Vector3f(static_cast<float>(R(0, 0) * lx + R(0, 1) * ly + R(0, 2) * lz + t_[0]),
                                static_cast<float>(R(1, 0) * lx + R(1, 1) * ly + R(1, 2) * lz + t_[1]),
                                static_cast<float>(R(2, 0) * lx + R(2, 1) * ly + R(2, 2) * lz + t_[2]));
    if (ranges) ranges[kept] = static_cast<float>(std::sqrt(lx * lx + ly * ly + lz * lz));
    ++kept;
  }
  return kept;
}

// Arrays of one point cloud that disagree in length (a damaged or hand-made observation): read
// past the shortest, they would be undefined behaviour.
void requireSameSizes(const char* what, std::size_t x, std::size_t y, std::size_t z) {
  if (x != y || x != z)
    throw std::invalid_argument(std::string("rtog::CRTreeOccupancyGridMap: ") + what + " arrays differ in length (x " +
                                std::to_string(x) + ", y " + std::to_string(y) + ", z " + std::to_string(z) + ")");
}

// Points of a points map (sensor frame), every `dec`-th.
void takePointsMap(const mrpt::maps::CPointsMap& pm, std::size_t dec, SensorPoints& sp) {
  const auto& xs = pm.getPointsBufferRef_x();
  const auto& ys = pm.getPointsBufferRef_y();
  const auto& zs = pm.getPointsBufferRef_z();
  requireSameSizes("points map", xs.size(), ys.size(), zs.size());
  sp.x = xs.data(), sp.y = ys.data(), sp.z = zs.data();
  sp.n = xs.size();
  sp.dec = dec;
}

// Points decoded into `local` (sensor frame, valid, decimated already).
void takeLocal(const std::vector<Eigen::Vector3f>& local, SensorPoints& sp) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f: three packed floats");
  const float* first = local.empty() ? nullptr : local.front().data();
  sp.x = first, sp.y = first ? first + 1 : nullptr, sp.z = first ? first + 2 : nullptr;
  sp.stride = 3;
  sp.n = local.size();
  sp.dec = 1;
}

// Keys of the sensor-frame point cache: everything the decoded points depend on.
std::uint64_t keyVelodyne(const mrpt::obs::CObservationVelodyneScan& v, std::size_t dec) {
  Fingerprint f;
  f.value(std::uint32_t{2});
  f.value(dec);
  f.value(v.minRange);
  f.value(v.maxRange);
  f.vector(v.point_cloud.x);
  f.vector(v.point_cloud.y);
  f.vector(v.point_cloud.z);
  f.vector(v.scan_packets);
  f.vector(v.calibration.laser_corrections);
  return f.digest();
}

std::uint64_t keyDepth(const mrpt::obs::CObservation3DRangeScan& d, std::size_t dec) {
  Fingerprint f;
  f.value(std::uint32_t{4});
  f.value(dec);
  f.value(d.rangeImage.rows());
  f.value(d.rangeImage.cols());
  f.bytes(d.rangeImage.data(), std::size_t(d.rangeImage.rows()) * std::size_t(d.rangeImage.cols()) * 2);
  f.value(d.rangeUnits);
  f.value(d.range_is_depth);
  // The whole camera model the unprojection reads (MRPT's undistorts every ray through `dist`,
  // at every decimation); the sensor pose is not in it: the points are in the sensor frame.
  const auto& c = d.cameraParams;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) f.value(c.intrinsicParams(i, j));
  for (double v : c.dist) f.value(v);
  f.value(static_cast<int>(c.distortion));
  f.value(c.nrows);
  f.value(c.ncols);
  return f.digest();
}

}  // namespace rtog::detail
