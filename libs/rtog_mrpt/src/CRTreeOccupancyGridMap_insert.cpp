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

// A pose's rotation and translation taken out once per observation: CPose3D::composePoint is
// a library call per point. Same arithmetic, same order.
struct Frame {
  explicit Frame(const CPose3D& pose) : R(pose.getRotationMatrix()), t{pose.x(), pose.y(), pose.z()} {}
  mrpt::math::CMatrixDouble33 R;
  double t[3];
};

// Appends the points get(i, x, y, z) gives for i = 0, dec, 2 dec, ... < n (false: an invalid
// one, counted), moved by the frame, written into buffers sized once: a depth frame has a
// quarter of a million points, and pushing each back into three vectors tests three capacities.
template <class Get>
void addFramePoints(const Frame& f, std::size_t n, std::size_t dec, Get&& get, ObservationBeams& out) {
  const std::size_t room = (n + dec - 1) / dec, base = out.points.size(), hits = out.is_hit.size(),
                    ranged = out.ranges.size();
  out.points.resize(base + room);
  if (out.with_ranges) out.ranges.resize(ranged + room);
  Eigen::Vector3f* pts = out.points.data() + base;
  float* ranges = out.with_ranges ? out.ranges.data() + ranged : nullptr;
  const auto& R = f.R;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; i += dec) {
    double lx, ly, lz;
    if (!get(i, lx, ly, lz)) {
      ++out.invalid;
      continue;
    }
    pts[kept] = Eigen::Vector3f(static_cast<float>(R(0, 0) * lx + R(0, 1) * ly + R(0, 2) * lz + f.t[0]),
                                static_cast<float>(R(1, 0) * lx + R(1, 1) * ly + R(1, 2) * lz + f.t[1]),
                                static_cast<float>(R(2, 0) * lx + R(2, 1) * ly + R(2, 2) * lz + f.t[2]));
    if (ranges) ranges[kept] = static_cast<float>(std::sqrt(lx * lx + ly * ly + lz * lz));
    ++kept;
  }
  out.points.resize(base + kept);
  if (out.with_ranges) out.ranges.resize(ranged + kept);
  out.is_hit.resize(hits + kept, 1);
}

void setOrigin(const CPose3D& sensor, ObservationBeams& out) {
  out.origin = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
}

// Points of a points map, given in the frame `frame`, into `out`.
void addPointsMap(const mrpt::maps::CPointsMap& pm, const CPose3D& frame, std::size_t decimation,
                  ObservationBeams& out) {
  const auto& xs = pm.getPointsBufferRef_x();
  const auto& ys = pm.getPointsBufferRef_y();
  const auto& zs = pm.getPointsBufferRef_z();
  addFramePoints(Frame(frame), xs.size(), decimation, [&](std::size_t i, double& x, double& y, double& z) {
    if (!std::isfinite(xs[i]) || !std::isfinite(ys[i]) || !std::isfinite(zs[i])) return false;
    x = xs[i], y = ys[i], z = zs[i];
    return true;
  }, out);
}

void addLocalPoints(const CPose3D& sensor, const std::vector<Eigen::Vector3f>& local, ObservationBeams& out) {
  addFramePoints(Frame(sensor), local.size(), 1, [&](std::size_t i, double& x, double& y, double& z) {
    x = local[i].x(), y = local[i].y(), z = local[i].z();
    return true;
  }, out);
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
  const auto& c = d.cameraParams;
  for (double v : {c.fx(), c.fy(), c.cx(), c.cy()}) f.value(v);
  f.value(c.nrows);
  f.value(c.ncols);
  return f.digest();
}

}  // namespace

std::shared_ptr<const CRTreeOccupancyGridMap::Caches::ScanAngles> CRTreeOccupancyGridMap::scanAngles(
    const mrpt::obs::CObservation2DRangeScan& scan) const {
  const std::size_t n = scan.getScanSize();
  {
    std::lock_guard<std::mutex> lk(caches_.mutex);
    const auto& a = caches_.scan_angles;
    if (a && a->beams == n && a->aperture == scan.aperture && a->right_to_left == scan.rightToLeft) return a;
  }
  auto table = std::make_shared<Caches::ScanAngles>();
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
  std::lock_guard<std::mutex> lk(caches_.mutex);
  caches_.scan_angles = table;
  return table;
}

template <class Decode>
void CRTreeOccupancyGridMap::localPointsCached(std::uint64_t key, Decode&& decode, std::vector<Eigen::Vector3f>& pts,
                                               std::size_t& invalid) const {
  {
    std::lock_guard<std::mutex> lk(caches_.mutex);
    if (caches_.local_valid && caches_.local_key == key) {
      pts = caches_.local_points;
      invalid = caches_.local_invalid;
      return;
    }
  }
  pts.clear();
  invalid = 0;
  decode(pts, invalid);
  std::lock_guard<std::mutex> lk(caches_.mutex);
  caches_.local_valid = true;
  caches_.local_key = key;
  caches_.local_points = pts;
  caches_.local_invalid = invalid;
}

bool CRTreeOccupancyGridMap::extractBeams(const mrpt::obs::CObservation& obs, const CPose3D& robotPose,
                                          ObservationBeams& out, bool forInsertion) const {
  using namespace mrpt::obs;
  out.clear();  // not replaced: callers reuse `out` and its capacity
  out.with_ranges = !forInsertion;
  // Scratch for the sensor-frame points, kept per thread from call to call.
  thread_local std::vector<Eigen::Vector3f> local;
  std::size_t dec = insertionOptions.decimation;
  if (!forInsertion)
    dec = likelihoodOptions.likelihoodMethod == lmRayTracing ? likelihoodOptions.rayTracing_decimation
                                                             : likelihoodOptions.LF_decimation;
  dec = std::max<std::size_t>(dec, 1);

  if (const auto* scan = dynamic_cast<const CObservation2DRangeScan*>(&obs)) {
    const CPose3D sensor = robotPose + scan->sensorPose;
    setOrigin(sensor, out);
    // A level scan's end points all get the float of the sensor z; the origin gets the same
    // value, so that a sensor a hair off a cell face does not trace from the layer next to its
    // end points'.
    const auto R = sensor.getRotationMatrix();
    if (R(2, 0) == 0.0 && R(2, 1) == 0.0) out.origin.z() = static_cast<double>(static_cast<float>(sensor.z()));
    // Decoded at every call, not cached: the beam angles' cos/sin are cached, and fingerprinting
    // the ranges would cost as much as this loop.
    {
      const std::size_t n = scan->getScanSize();
      const auto angles = scanAngles(*scan);
      local.clear();
      local.reserve(n / dec + 1);
      for (std::size_t i = 0; i < n; i += dec) {
        const float r = scan->getScanRange(i);
        if (!scan->getScanRangeValidity(i) || !std::isfinite(r) || !(r > 0.0f)) {
          ++out.invalid;
          continue;
        }
        local.emplace_back(static_cast<float>(r * angles->cos[i]), static_cast<float>(r * angles->sin[i]), 0.0f);
      }
    }
    addLocalPoints(sensor, local, out);
    return true;
  }
  if (const auto* range = dynamic_cast<const CObservationRange*>(&obs)) {
    // Insertion takes the readings as cones (insertSonar), never as beams; for the likelihood
    // they are the echoes on the axes.
    if (forInsertion) return false;
    sonarEndPoints(*range, robotPose, out);
    return true;
  }
  if (const auto* pc = dynamic_cast<const CObservationPointCloud*>(&obs)) {
    pc->load();
    if (!pc->pointcloud) return false;
    const CPose3D sensor = robotPose + pc->sensorPose;
    setOrigin(sensor, out);
    addPointsMap(*pc->pointcloud, sensor, dec, out);
    return true;
  }
  if (const auto* velo = dynamic_cast<const CObservationVelodyneScan*>(&obs)) {
    const CPose3D sensor = robotPose + velo->sensorPose;
    setOrigin(sensor, out);
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
        local, out.invalid);
    addLocalPoints(sensor, local, out);
    return true;
  }
  if (const auto* rot = dynamic_cast<const CObservationRotatingScan*>(&obs)) {
    const CPose3D sensor = robotPose + rot->sensorPose;
    setOrigin(sensor, out);
    // Not cached: fingerprinting the whole range image costs more than decoding it.
    local.clear();
    detail::decodeRotatingScan(*rot, dec, insertionOptions.rotatingScan_minElevation_deg,
                               insertionOptions.rotatingScan_maxElevation_deg, local, out.invalid);
    addLocalPoints(sensor, local, out);
    return true;
  }
  if (const auto* depth = dynamic_cast<const CObservation3DRangeScan*>(&obs)) {
    depth->load();
    const CPose3D sensor = robotPose + depth->sensorPose;
    const Frame frame(sensor);
    if (!depth->hasRangeImage) {
      if (!depth->hasPoints3D) return false;
      requireSameSizes("CObservation3DRangeScan points3D", depth->points3D_x.size(), depth->points3D_y.size(),
                       depth->points3D_z.size());
      // Only the point cloud was stored (sensor frame).
      setOrigin(sensor, out);
      const auto& xs = depth->points3D_x;
      const auto& ys = depth->points3D_y;
      const auto& zs = depth->points3D_z;
      addFramePoints(frame, xs.size(), dec, [&](std::size_t i, double& x, double& y, double& z) {
        if (!std::isfinite(xs[i]) || !std::isfinite(ys[i]) || !std::isfinite(zs[i]) ||
            (xs[i] == 0 && ys[i] == 0 && zs[i] == 0))
          return false;
        x = xs[i], y = ys[i], z = zs[i];
        return true;
      }, out);
      return true;
    }
    setOrigin(sensor, out);
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
        local, out.invalid);
    addLocalPoints(sensor, local, out);
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
  ObservationBeams beams;
  if (!extractBeams(obs, robotPose ? *robotPose : CPose3D(), beams, true)) return false;
  syncParams();
  const InsertParams ip = insertionOptions.toInsertParams();
  lastInsertStats = map_.insertPointCloud(beams.origin, beams.points.data(), beams.points.size(), ip,
                                          beams.is_hit.data());
  totalInsertStats += lastInsertStats;
  invalidRangesSkipped += beams.invalid;
  notifyMapChanged();
  return true;
}

}  // namespace rtog
