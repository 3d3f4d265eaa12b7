#include "sensor_points.hpp"

#include <cmath>

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

}  // namespace rtog::detail
