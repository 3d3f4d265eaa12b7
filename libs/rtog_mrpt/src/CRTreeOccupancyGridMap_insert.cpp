// rtog::CRTreeOccupancyGridMap: turning MRPT observations into beams and inserting them, at a
// pose or an uncertain pose. The sensor specifics are helpers: sensor_points.hpp (point clouds,
// depth, Velodyne), sonar_cones.hpp (CObservationRange as cones), pose_sigma.hpp (the sigma
// points of a pose covariance); 2D scans of the mrpt_grid preset are in CRTreeOccupancyGridMap_grid2d.cpp.
#include <cmath>
#include <stdexcept>
#include <string>

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "depth_unprojection.hpp"
#include "fingerprint.hpp"
#include "rotating_scan.hpp"
#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "mrpt_grid.hpp"
#include "pose_sigma.hpp"
#include "sensor_points.hpp"
#include "sonar_cones.hpp"
#include "CRTreeOccupancyGridMap_caches.hpp"

namespace rtog {

using mrpt::poses::CPose3D;

std::shared_ptr<const CRTreeOccupancyGridMap::ScanAngles> CRTreeOccupancyGridMap::scanAngles(
    const mrpt::obs::CObservation2DRangeScan& scan) const {
  const std::size_t n = scan.getScanSize();
  {
    std::lock_guard<std::mutex> lk(caches_->mutex);
    const auto& a = caches_->scan_angles;
    if (a && a->beams == n && a->aperture == scan.aperture && a->right_to_left == scan.rightToLeft) return a;
  }
  auto table = std::make_shared<ScanAngles>();
  table->beams = n;
  table->aperture = scan.aperture;
  table->right_to_left = scan.rightToLeft;
  for (std::size_t i = 0; i < n; ++i) {
    // MRPT's getScanAngle() divides the aperture by n - 1, which makes the one ray of a 1-beam
    // scan NaN (and the beam a skip). COccupancyGridMap2D casts it at the first ray's angle, as
    // getScanAngle(0) would be: -aperture/2 for a scan from right to left, +aperture/2 else.
    const double a = n == 1 ? (scan.rightToLeft ? -0.5f : 0.5f) * scan.aperture : scan.getScanAngle(i);
    table->cos.push_back(std::cos(a));
    table->sin.push_back(std::sin(a));
  }
  std::lock_guard<std::mutex> lk(caches_->mutex);
  caches_->scan_angles = table;
  return table;
}

template <class Decode>
void CRTreeOccupancyGridMap::localPointsCached(std::uint64_t key, Decode&& decode, std::vector<Eigen::Vector3f>& pts,
                                               std::size_t& invalid) const {
  {
    std::lock_guard<std::mutex> lk(caches_->mutex);
    if (caches_->local_valid && caches_->local_key == key) {
      pts = caches_->local_points;
      invalid = caches_->local_invalid;
      return;
    }
  }
  pts.clear();
  invalid = 0;
  decode(pts, invalid);
  std::lock_guard<std::mutex> lk(caches_->mutex);
  caches_->local_valid = true;
  caches_->local_key = key;
  caches_->local_points = pts;
  caches_->local_invalid = invalid;
}

bool CRTreeOccupancyGridMap::extractBeams(const mrpt::obs::CObservation& obs, const CPose3D& robotPose,
                                          ObservationBeams& out, bool forInsertion) const {
  out.clear();  // not replaced: callers reuse `out` and its capacity
  out.with_ranges = !forInsertion;
  if (const auto* range = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) {
    // Insertion takes the readings as cones (insertSonar), never as beams; for the likelihood
    // they are the echoes on the axes.
    if (forInsertion) return false;
    sonar::endPoints(*range, robotPose, out);
    return true;
  }
  detail::SensorPoints sp;
  if (!sensorPoints(obs, robotPose, forInsertion, sp)) return false;
  out.origin = sp.origin;
  out.invalid = sp.invalid;
  const std::size_t room = sp.size();
  out.points.resize(room);
  if (out.with_ranges) out.ranges.resize(room);
  float* ranges = out.with_ranges ? out.ranges.data() : nullptr;
  const std::size_t kept = sp.read(0, room, out.points.data(), ranges, out.invalid);
  out.points.resize(kept);
  if (out.with_ranges) out.ranges.resize(kept);
  out.is_hit.resize(kept, 1);
  return true;
}

bool CRTreeOccupancyGridMap::sensorPoints(const mrpt::obs::CObservation& obs, const CPose3D& robotPose,
                                          bool forInsertion, detail::SensorPoints& sp) const {
  using namespace mrpt::obs;
  // Scratch for decoded sensor-frame points, kept per thread from call to call; `sp` points
  // into it until this thread's next call.
  thread_local std::vector<Eigen::Vector3f> local;
  local.clear();
  std::size_t dec = insertionOptions.decimation;
  if (!forInsertion)
    dec = likelihoodOptions.likelihoodMethod == lmRayTracing ? likelihoodOptions.rayTracing_decimation
                                                             : likelihoodOptions.LF_decimation;
  dec = std::max<std::size_t>(dec, 1);

  if (const auto* scan = dynamic_cast<const CObservation2DRangeScan*>(&obs)) {
    const CPose3D sensor = robotPose + scan->sensorPose;
    sp.setSensor(sensor);
    // A level scan's end points all get the float of the sensor z; the origin gets the same
    // value, so that a sensor a hair off a cell face does not trace from the layer next to its
    // end points'.
    const auto R = sensor.getRotationMatrix();
    if (R(2, 0) == 0.0 && R(2, 1) == 0.0) sp.origin.z() = static_cast<double>(static_cast<float>(sensor.z()));
    // Decoded at every call, not cached: the beam angles' cos/sin are cached, and fingerprinting
    // the ranges would cost as much as this loop.
    {
      const std::size_t n = scan->getScanSize();
      const auto angles = scanAngles(*scan);
      local.reserve(n / dec + 1);
      for (std::size_t i = 0; i < n; i += dec) {
        const float r = scan->getScanRange(i);
        if (!scan->getScanRangeValidity(i) || !std::isfinite(r) || !(r > 0.0f)) {
          ++sp.invalid;
          continue;
        }
        local.emplace_back(static_cast<float>(r * angles->cos[i]), static_cast<float>(r * angles->sin[i]), 0.0f);
      }
    }
    detail::takeLocal(local, sp);
    return true;
  }
  if (const auto* pc = dynamic_cast<const CObservationPointCloud*>(&obs)) {
    pc->load();
    if (!pc->pointcloud) return false;
    sp.setSensor(robotPose + pc->sensorPose);
    detail::takePointsMap(*pc->pointcloud, dec, sp);
    return true;
  }
  if (const auto* velo = dynamic_cast<const CObservationVelodyneScan*>(&obs)) {
    sp.setSensor(robotPose + velo->sensorPose);
    localPointsCached(
        detail::keyVelodyne(*velo, dec),
        [&](std::vector<Eigen::Vector3f>& pts, std::size_t& invalid) {
          CObservationVelodyneScan tmp;
          const CObservationVelodyneScan* src = velo;
          if (velo->point_cloud.size() == 0) {  // raw packets only: let MRPT decode them (sensor frame)
            tmp = *velo;
            tmp.generatePointCloud();
            src = &tmp;
          }
          const auto& pcl = src->point_cloud;
          detail::requireSameSizes("CObservationVelodyneScan point_cloud", pcl.x.size(), pcl.y.size(), pcl.z.size());
          for (std::size_t i = 0; i < pcl.x.size(); i += dec) {
            if (!std::isfinite(pcl.x[i]) || !std::isfinite(pcl.y[i]) || !std::isfinite(pcl.z[i])) {
              ++invalid;
              continue;
            }
            pts.emplace_back(pcl.x[i], pcl.y[i], pcl.z[i]);
          }
        },
        local, sp.invalid);
    detail::takeLocal(local, sp);
    return true;
  }
  if (const auto* rot = dynamic_cast<const CObservationRotatingScan*>(&obs)) {
    sp.setSensor(robotPose + rot->sensorPose);
    // Not cached: fingerprinting the whole range image costs more than decoding it.
    detail::decodeRotatingScan(*rot, dec, insertionOptions.rotatingScan_minElevation_deg,
                               insertionOptions.rotatingScan_maxElevation_deg, local, sp.invalid);
    detail::takeLocal(local, sp);
    return true;
  }
  if (const auto* depth = dynamic_cast<const CObservation3DRangeScan*>(&obs)) {
    depth->load();
    sp.setSensor(robotPose + depth->sensorPose);
    if (!depth->hasRangeImage) {
      if (!depth->hasPoints3D) return false;
      // Only the point cloud was stored (sensor frame).
      detail::requireSameSizes("CObservation3DRangeScan points3D", depth->points3D_x.size(), depth->points3D_y.size(),
                       depth->points3D_z.size());
      sp.x = depth->points3D_x.data(), sp.y = depth->points3D_y.data(), sp.z = depth->points3D_z.data();
      sp.n = depth->points3D_x.size();
      sp.dec = dec;
      sp.zero_is_invalid = true;
      return true;
    }
    // MRPT's unprojection through the camera model, into the sensor frame (x forward), once
    // per observation; then the sensor pose on the robot and the robot pose. Decimated, the
    // same points without the table of every pixel MRPT would keep (depth_unprojection.hpp).
    const std::size_t ddec = forInsertion ? insertionOptions.decimation_3d_range : std::min<std::size_t>(dec, 255);
    localPointsCached(
        detail::keyDepth(*depth, ddec),
        [&](std::vector<Eigen::Vector3f>& pts, std::size_t& invalid) {
          if (ddec > 1) {
            detail::unprojectDecimated(*depth, ddec, pts, invalid);
            return;
          }
          mrpt::maps::CSimplePointsMap pm;
          mrpt::obs::T3DPointsProjectionParams pp;
          pp.takeIntoAccountSensorPoseOnRobot = false;
          const_cast<CObservation3DRangeScan*>(depth)->unprojectInto(pm, pp);
          const std::size_t pixels =
              static_cast<std::size_t>(depth->rangeImage.rows()) * static_cast<std::size_t>(depth->rangeImage.cols());
          const auto& xs = pm.getPointsBufferRef_x();
          const auto& ys = pm.getPointsBufferRef_y();
          const auto& zs = pm.getPointsBufferRef_z();
          pts.reserve(xs.size());
          for (std::size_t i = 0; i < xs.size(); ++i) {
            if (!std::isfinite(xs[i]) || !std::isfinite(ys[i]) || !std::isfinite(zs[i])) {
              ++invalid;
              continue;
            }
            pts.emplace_back(xs[i], ys[i], zs[i]);
          }
          invalid += pixels > xs.size() ? pixels - xs.size() : 0;
        },
        local, sp.invalid);
    detail::takeLocal(local, sp);
    return true;
  }
  return false;
}

bool CRTreeOccupancyGridMap::internal_insertObservation(const mrpt::obs::CObservation& obs,
                                                        const std::optional<const CPose3D>& robotPose) {
  if (const auto* range = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs))
    return insertSonar(*range, robotPose ? *robotPose : CPose3D());
  if (insertionOptions.mrptGrid()) {
    // A 3D section: every observation (sonar above) as COccupancyGridMap3D. Otherwise 2D scans as
    // COccupancyGridMap2D, and 3D observations (which that grid does not take) below.
    if (frame3d_.defined) return insertGrid3D(obs, {pose_sigma::SigmaPose{1.0, robotPose ? *robotPose : CPose3D()}});
    if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs))
      return insertGridScan(*scan, robotPose ? *robotPose : CPose3D());
  }
  detail::SensorPoints sp;
  if (!sensorPoints(obs, robotPose ? *robotPose : CPose3D(), true, sp)) return false;
  syncParams();
  const InsertParams ip = insertionOptions.toInsertParams();
  // Read by the insertion threads, moved into the map frame piece by piece. Every point taken
  // is a beam the map counts or an invalid one.
  const PointSource source{sp.size(), [&sp](std::size_t first, std::size_t n, Eigen::Vector3f* out) {
                             std::size_t dropped = 0;
                             return sp.read(first, n, out, nullptr, dropped);
                           }};
  lastInsertStats = map_.insertPointSource(sp.origin, source, ip);
  totalInsertStats += lastInsertStats;
  invalidRangesSkipped += sp.invalid + (sp.size() - lastInsertStats.raysTotal());
  notifyMapChanged();
  return true;
}


// ---- sonar cones (sonar_cones.hpp)

std::vector<ConeReading> CRTreeOccupancyGridMap::sonarReadings(const mrpt::obs::CObservationRange& o,
                                                               const CPose3D& robotPose, std::size_t& invalid) const {
  return sonar::readings(o, robotPose, insertionOptions, invalid);
}

bool CRTreeOccupancyGridMap::insertSonar(const mrpt::obs::CObservationRange& o, const CPose3D& robotPose) {
  syncParams();
  std::size_t invalid = 0;
  const std::vector<ConeReading> readings = sonarReadings(o, robotPose, invalid);
  InsertStats stats;
  if (!insertionOptions.mrptGrid())
    stats = map_.insertCones(readings.data(), readings.size(),
                             coneWeightingFromString(insertionOptions.sonarConeWeighting),
                             insertionOptions.toInsertParams());
  else
    stats = sonar::insertOnGrid(map_, frame_, readings, insertionOptions);
  invalidRangesSkipped += invalid;
  lastInsertStats = stats;
  totalInsertStats += stats;
  notifyMapChanged();
  return true;
}

// ---- uncertain poses (poseUncertainty, doc/pose-uncertainty.md) ----------------------------

bool CRTreeOccupancyGridMap::insertObservation(const mrpt::obs::CObservation& obs,
                                               const mrpt::poses::CPose3DPDFGaussian& pose) {
  if (!insertionOptions.poseUncertainty) return insertObservation(obs, pose.mean);
  // A sonar reading already spreads over its cone: inserted at the mean (doc/sonar.md).
  if (dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) return insertObservation(obs, pose.mean);
  const std::vector<pose_sigma::SigmaPose> sigma = pose_sigma::sigmaPoses(pose);  // throws for a bad covariance
  if (sigma.size() == 1) return insertObservation(obs, pose.mean);  // a certain pose: the plain update
  if (!genericMapParams.enableObservationInsertion) return false;
  if (insertionOptions.mrptGrid()) {
    // On the grids' rasters, as the observation at a certain pose is (grid_graded.hpp).
    const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs);
    bool inserted = false, handled = true;
    if (frame3d_.defined)
      inserted = insertGrid3D(obs, sigma);
    else if (scan)
      inserted = insertGradedScan(*scan, sigma);
    else
      handled = false;  // a 3D observation of a 2D section: the core's mixture, on the int8 lattice
    if (handled) {
      if (inserted) publishEvent(mrpt::maps::mrptEventMetricMapInsert(this, &obs, pose.mean));
      return inserted;
    }
  }
  // Traced once at the mean and moved to each sigma pose (OccupancyMap::insertBlurred).
  ObservationBeams beams;
  if (!extractBeams(obs, pose.mean, beams, true)) return false;
  const std::vector<PoseMove> moves = pose_sigma::poseMoves(sigma, pose.mean);
  syncParams();
  lastInsertStats = map_.insertBlurred(beams.origin, beams.points.data(), beams.points.size(), moves.data(), moves.size(),
                                       insertionOptions.toInsertParams(), beams.is_hit.data());
  totalInsertStats += lastInsertStats;
  invalidRangesSkipped += beams.invalid;
  notifyMapChanged();
  publishEvent(mrpt::maps::mrptEventMetricMapInsert(this, &obs, pose.mean));
  return true;
}

bool CRTreeOccupancyGridMap::insertObservation(const mrpt::obs::CObservation& obs,
                                               const mrpt::poses::CPosePDFGaussian& pose) {
  return insertObservation(obs, mrpt::poses::CPose3DPDFGaussian(pose));
}

void CRTreeOccupancyGridMap::loadFromProbabilisticPosesAndObservations(const mrpt::maps::CSimpleMap& sm) {
  clear();
  for (const auto& pair : sm) {
    if (!pair.pose) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a simplemap frame has no pose");
    if (!pair.sf) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: a simplemap frame has no observations");
    mrpt::poses::CPose3DPDFGaussian g;
    g.copyFrom(*pair.pose);  // a particle or mixture PDF as its mean and covariance
    for (const auto& obs : *pair.sf)
      if (obs) insertObservation(*obs, g);
  }
}

}  // namespace rtog
