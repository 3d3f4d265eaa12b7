// rtog::CRTreeOccupancyGridMap: MRPT's 2D sensor simulators on the 2D view, and the native 3D
// ray and nearest-obstacle queries.
#include <cmath>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationRange.h>

#include "CRTreeOccupancyGridMap_grid2d.hpp"

namespace rtog {

void CRTreeOccupancyGridMap::laserScanSimulator(mrpt::obs::CObservation2DRangeScan& scan,
                                                const mrpt::poses::CPose2D& robotPose, float threshold, size_t N,
                                                float noiseStd, unsigned int decimation, float angleNoiseStd) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  v->grid.laserScanSimulator(scan, robotPose, threshold, N, noiseStd, decimation, angleNoiseStd);
}

void CRTreeOccupancyGridMap::sonarSimulator(mrpt::obs::CObservationRange& obs, const mrpt::poses::CPose2D& robotPose,
                                            float threshold, float rangeNoiseStd, float angleNoiseStd) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  v->grid.sonarSimulator(obs, robotPose, threshold, rangeNoiseStd, angleNoiseStd);
}

void CRTreeOccupancyGridMap::simulateScanRay(double x, double y, double angle, float& out_range, bool& out_valid,
                                             double max_range, float threshold_free, double noiseStd,
                                             double angleNoiseStd) const {
  const auto v = gridViewShared();
  std::lock_guard<std::mutex> lk(v->mutex);
  v->grid.simulateScanRay(x, y, angle, out_range, out_valid, max_range, threshold_free, noiseStd, angleNoiseStd);
}

std::optional<double> CRTreeOccupancyGridMap::castRay(const mrpt::math::TPoint3D& origin,
                                                      const mrpt::math::TVector3D& direction, double maxRange) const {
  const Eigen::Vector3d o(origin.x, origin.y, origin.z), d(direction.x, direction.y, direction.z);
  if (!o.allFinite() || !d.allFinite() || !(d.squaredNorm() > 0) || !(maxRange > 0)) return std::nullopt;
  const auto h = map_.castRay(o, d, maxRange);
  if (!h.hit || h.distance > maxRange) return std::nullopt;
  return h.distance;
}

std::optional<double> CRTreeOccupancyGridMap::nearestObstacleDistance(const mrpt::math::TPoint3D& p,
                                                                      double maxDistance) const {
  const Eigen::Vector3d q(p.x, p.y, p.z);
  if (!q.allFinite() || !(maxDistance >= 0)) return std::nullopt;
  const auto h = map_.nearestOccupied(q, maxDistance);
  if (!h.found || h.distance > maxDistance) return std::nullopt;
  return h.distance;
}

}  // namespace rtog
