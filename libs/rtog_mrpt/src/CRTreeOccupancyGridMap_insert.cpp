// rtog::CRTreeOccupancyGridMap: turning MRPT observations into beams and inserting them.
#include <cmath>
#include <stdexcept>
#include <string>

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "depth_unprojection.hpp"
#include "fingerprint.hpp"
#include "rotating_scan.hpp"
#include "sensor_points.hpp"
#include "CRTreeOccupancyGridMap_caches.hpp"

namespace rtog {

using mrpt::poses::CPose3D;

namespace {

// Arrays of one point cloud that disagree in length (a damaged or hand-made observation): read
// past the shortest, they would be undefined behaviour.
void requireSameSizes(const char* what, std::size_t x, std::size_t y, std::size_t z) {
  if (x != y || x != z)
    throw std::invalid_argument(std::string("rtog::CRTreeOccupancyGridMap: ") + what + " arrays differ in length (x " +
                                std::to_string(x) + ", y " + std::to_string(y) + ", z " + std::to_string(z) + ")");
}

// Points of a points map (sensor frame), every `dec`-th.
void takePointsMap(const mrpt::maps::CPointsMap& pm, std::size_t dec, detail::SensorPoints& sp) {
  const auto& xs = pm.getPointsBufferRef_x();
  const auto& ys = pm.getPointsBufferRef_y();
  const auto& zs = pm.getPointsBufferRef_z();
  requireSameSizes("points map", xs.size(), ys.size(), zs.size());
  sp.x = xs.data(), sp.y = ys.data(), sp.z = zs.data();
  sp.n = xs.size();
  sp.dec = dec;
}

// Points decoded into `local` (sensor frame, valid, decimated already).
void takeLocal(const std::vector<Eigen::Vector3f>& local, detail::SensorPoints& sp) {
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "Vector3f: three packed floats");
  const float* first = local.empty() ? nullptr : local.front().data();
  sp.x = first, sp.y = first ? first + 1 : nullptr, sp.z = first ? first + 2 : nullptr;
  sp.stride = 3;
  sp.n = local.size();
  sp.dec = 1;
}

// Keys of the sensor-frame point cache: everything the decoded points depend on.
std::uint64_t keyVelodyne(const mrpt::obs::CObservationVelodyneScan& v, std::size_t dec) {
  detail::Fingerprint f;
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
  detail::Fingerprint f;
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

}  // namespace

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
    sonarEndPoints(*range, robotPose, out);
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
    takeLocal(local, sp);
    return true;
  }
  if (const auto* pc = dynamic_cast<const CObservationPointCloud*>(&obs)) {
    pc->load();
    if (!pc->pointcloud) return false;
    sp.setSensor(robotPose + pc->sensorPose);
    takePointsMap(*pc->pointcloud, dec, sp);
    return true;
  }
  if (const auto* velo = dynamic_cast<const CObservationVelodyneScan*>(&obs)) {
    sp.setSensor(robotPose + velo->sensorPose);
    localPointsCached(
        keyVelodyne(*velo, dec),
        [&](std::vector<Eigen::Vector3f>& pts, std::size_t& invalid) {
          CObservationVelodyneScan tmp;
          const CObservationVelodyneScan* src = velo;
          if (velo->point_cloud.size() == 0) {  // raw packets only: let MRPT decode them (sensor frame)
            tmp = *velo;
            tmp.generatePointCloud();
            src = &tmp;
          }
          const auto& pcl = src->point_cloud;
          requireSameSizes("CObservationVelodyneScan point_cloud", pcl.x.size(), pcl.y.size(), pcl.z.size());
          for (std::size_t i = 0; i < pcl.x.size(); i += dec) {
            if (!std::isfinite(pcl.x[i]) || !std::isfinite(pcl.y[i]) || !std::isfinite(pcl.z[i])) {
              ++invalid;
              continue;
            }
            pts.emplace_back(pcl.x[i], pcl.y[i], pcl.z[i]);
          }
        },
        local, sp.invalid);
    takeLocal(local, sp);
    return true;
  }
  if (const auto* rot = dynamic_cast<const CObservationRotatingScan*>(&obs)) {
    sp.setSensor(robotPose + rot->sensorPose);
    // Not cached: fingerprinting the whole range image costs more than decoding it.
    detail::decodeRotatingScan(*rot, dec, insertionOptions.rotatingScan_minElevation_deg,
                               insertionOptions.rotatingScan_maxElevation_deg, local, sp.invalid);
    takeLocal(local, sp);
    return true;
  }
  if (const auto* depth = dynamic_cast<const CObservation3DRangeScan*>(&obs)) {
    depth->load();
    sp.setSensor(robotPose + depth->sensorPose);
    if (!depth->hasRangeImage) {
      if (!depth->hasPoints3D) return false;
      // Only the point cloud was stored (sensor frame).
      requireSameSizes("CObservation3DRangeScan points3D", depth->points3D_x.size(), depth->points3D_y.size(),
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
        keyDepth(*depth, ddec),
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
    takeLocal(local, sp);
    return true;
  }
  return false;
}

bool CRTreeOccupancyGridMap::internal_insertObservation(const mrpt::obs::CObservation& obs,
                                                        const std::optional<const CPose3D>& robotPose) {
  if (insertionOptions.mrptGrid())
    if (const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs))
      return insertGridScan(*scan, robotPose ? *robotPose : CPose3D());
  if (const auto* range = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs))
    return insertSonar(*range, robotPose ? *robotPose : CPose3D());
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

}  // namespace rtog
