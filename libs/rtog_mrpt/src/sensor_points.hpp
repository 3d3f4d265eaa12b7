// An observation's beams in its sensor's frame, moved into the map frame by whoever reads them:
// whole, for the likelihood (extractBeams), or piece by piece by the insertion threads (a
// PointSource), so that a depth frame is never copied whole into the map frame first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/poses/CPose3D.h>

namespace rtog::detail {

struct SensorPoints {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< the sensor, map frame
  /// The points: point i at (x[i * stride], y[i * stride], z[i * stride]), sensor frame; every
  /// dec-th of the n taken.
  const float* x = nullptr;
  const float* y = nullptr;
  const float* z = nullptr;
  std::size_t stride = 1, n = 0, dec = 1;
  bool zero_is_invalid = false;  ///< a depth camera's pixel without depth reads (0, 0, 0)
  std::size_t invalid = 0;       ///< beams dropped while decoding, before these points

  /// The sensor's pose in the map frame (rotation and translation taken out once: composing a
  /// CPose3D is a library call per point).
  void setSensor(const mrpt::poses::CPose3D& sensor);
  /// Points taken (valid or not).
  std::size_t size() const { return (n + dec - 1) / dec; }
  /// Writes the valid ones of the points taken j in [first, first + m), in order, into `out`
  /// (map frame), and their sensor-frame ranges into `ranges` if not null; counts the invalid
  /// ones (a coordinate not finite; (0, 0, 0) if zero_is_invalid) in `dropped`. Returns how many
  /// it wrote. Reads only: called from several threads at once.
  std::size_t read(std::size_t first, std::size_t m, Eigen::Vector3f* out, float* ranges, std::size_t& dropped) const;

 private:
  mrpt::math::CMatrixDouble33 R_;
  double t_[3] = {0.0, 0.0, 0.0};
};

/// Throws std::invalid_argument where the arrays of one point cloud disagree in length (a
/// damaged or hand-made observation): read past the shortest, they would be undefined behaviour.
void requireSameSizes(const char* what, std::size_t x, std::size_t y, std::size_t z);
/// Points of a points map (sensor frame), every `dec`-th, into `sp`.
void takePointsMap(const mrpt::maps::CPointsMap& pm, std::size_t dec, SensorPoints& sp);
/// Points decoded into `local` (sensor frame, valid, decimated already), into `sp`.
void takeLocal(const std::vector<Eigen::Vector3f>& local, SensorPoints& sp);
/// Keys of the sensor-frame point cache: everything the decoded points depend on.
std::uint64_t keyVelodyne(const mrpt::obs::CObservationVelodyneScan& v, std::size_t dec);
std::uint64_t keyDepth(const mrpt::obs::CObservation3DRangeScan& d, std::size_t dec);

}  // namespace rtog::detail
