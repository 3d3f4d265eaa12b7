// The maps rtog-accuracy compares, each built from the same simulated scans and read back as
// one P(occupied) and one class per cell of the evaluation region.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include <mrpt/obs/CObservation2DRangeScan.h>

#include "rtog/core/log_odds.hpp"
#include "rtog/core/occupancy_map.hpp"
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
/// rtog's MRPT map type in the mrpt_grid preset (builders_mrpt_grid.cpp) with `v`'s model and
/// pose blur, MRPT's sensor model (kMrptOcc / kMrptFree): `planar` scans in a 2D section at `poses`,
/// otherwise (planar null) point clouds in a 3D section of the region's box.
MapView buildRtogMrptGrid(const std::vector<sim::Scan>& scans, const std::vector<sim::Pose>& poses,
                          const sim::ScannerParams* planar, double res, double max_range, const sim::TruthGrid& region,
                          const RtogVariant& v, const Eigen::Matrix3d& pose_cov);
/// The cells of `map` in the region into `out` (P(occupied) and class).
void readRtog(const OccupancyMap& map, const sim::TruthGrid& region, MapView& out);
/// OctoMap's OcTree with its default probabilities.
MapView buildOctomap(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region);
/// MRPT's COccupancyGridMap3D fed point clouds and no-return rays.
MapView buildMrpt3D(const std::vector<sim::Scan>& scans, double res, double max_range, const sim::TruthGrid& region);
/// Same sensor model as the others, as far as MRPT's options go: P(occ | hit) = 0.7 and
/// P(free | miss) = 0.6. (MRPT's grids triple the occupied log-odds increment internally.)
constexpr float kMrptOcc = 0.7f, kMrptFree = 0.6f;
/// A planar scan as the CObservation2DRangeScan an MRPT driver would write.
mrpt::obs::CObservation2DRangeScan scanObservation(const sim::Scan& scan, const sim::ScannerParams& sp);
/// MRPT's COccupancyGridMap2D fed CObservation2DRangeScans at `poses` (the ones the scans were
/// placed with: with pose noise, the believed poses).
MapView buildMrpt2D(const std::vector<sim::Scan>& scans, const std::vector<sim::Pose>& poses,
                    const sim::ScannerParams& sp, double res, const sim::TruthGrid& region);

}  // namespace rtog::accuracy
