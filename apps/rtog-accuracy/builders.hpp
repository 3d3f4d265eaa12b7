// The maps rtog-accuracy compares, each built from the same simulated scans and read back as
// one P(occupied) and one class per cell of the evaluation region.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/log_odds.hpp"
#include "rtog/core/params.hpp"
#include "rtog/sim/metrics.hpp"
#include "rtog/sim/sensors.hpp"
#include "rtog/sim/world.hpp"

namespace rtog::accuracy {

/// What one map says about every cell of the region: P(occupied) and its class.
struct MapView {
  std::string name;
  double insert_seconds = 0;
  std::vector<float> p;  // P(occupied); only meaningful when state != Unknown
  std::vector<sim::Predicted> state;
  std::size_t outside = 0;  // known cells outside the region
  MapView(std::string n, std::size_t cells)
      : name(std::move(n)), p(cells, 0.5f), state(cells, sim::Predicted::Unknown) {}
};

/// One of rtog's sensor models, with or without the pose covariance blurred into each scan.
struct RtogVariant {
  std::string name;                              ///< "rtog", "rtog_range_noise_pose_blur", ...
  SensorModel model = SensorModel::BeamBased;
  double range_sigma = 0.0;                      ///< RangeNoise: the sensor's own sigma [m]
  bool pose_blur = false;                        ///< insertBlurred() with the pose covariance
  LogOddsParams log_odds;                        ///< (Default: OctoMap's, as the other maps)
};

/// rtog with `v`; `pose_cov` is the covariance of (dx, dy, dyaw) of every scan's pose, used
/// when v.pose_blur (OccupancyMap::insertBlurred() over its sigma points).
MapView buildRtog(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region,
                  const RtogVariant& v, const Eigen::Matrix3d& pose_cov);
/// OctoMap's OcTree with its default probabilities.
MapView buildOctomap(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region);
/// MRPT's COccupancyGridMap3D fed point clouds and no-return rays.
MapView buildMrpt3D(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region);
/// MRPT's COccupancyGridMap2D fed CObservation2DRangeScans at `poses` (the ones the scans were
/// placed with: with pose noise, the believed poses).
MapView buildMrpt2D(const std::vector<sim::Scan>& scans, const std::vector<sim::Pose>& poses,
                    const sim::ScannerParams& sp, double res, const sim::TruthGrid& region);

}  // namespace rtog::accuracy
