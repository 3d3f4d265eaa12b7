// The mrpt_grid preset in 3D (mrpt_grid3d.hpp). Built with -ffp-contract=off, as mrpt_grid.cpp:
// the grid's arithmetic has no fused multiply-add.
#include "mrpt_grid3d.hpp"

#include "mrpt_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <mrpt/core/round.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/T3DPointsProjectionParams.h>

namespace rtog::mrpt_grid3d {

namespace {
constexpr int kFrBits = 9;  // the grid's fixed-point bits (FRBITS)

bool outside(const TGridFrame3D& f, int cx, int cy, int cz) {
  return cx < 0 || cx >= static_cast<int>(f.size_x) || cy < 0 || cy >= static_cast<int>(f.size_y) || cz < 0 ||
         cz >= static_cast<int>(f.size_z);
}
}  // namespace

StepRule stepRule(const CRTreeOccupancyGridMap::TInsertionOptions& io) {
  mrpt_grid::Steps s = mrpt_grid::stepsOf(io);
  s.noecho = s.free;
  return mrpt_grid::stepRule(s);
}

TGridFrame3D makeFrame(float x_min, float x_max, float y_min, float y_max, float z_min, float z_max, float resolution,
                       double latticeResolution) {
  const auto bad = [](const std::string& why) {
    throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: the 3D grid extent " + why);
  };
  if (!(std::isfinite(x_min) && std::isfinite(x_max) && x_min < x_max && std::isfinite(y_min) &&
        std::isfinite(y_max) && y_min < y_max && std::isfinite(z_min) && std::isfinite(z_max) && z_min < z_max))
    bad("needs finite min < max along x, y and z");
  if (!(std::isfinite(resolution) && resolution > 0.0f)) bad("needs a positive resolution");
  // CDynamicGrid3D::setSize, in its double arithmetic (mrpt::round: ties to even).
  TGridFrame3D f;
  f.defined = true;
  f.resolution = double{resolution};
  f.x_min = double{x_min}, f.y_min = double{y_min}, f.z_min = double{z_min};
  const double r = f.resolution;
  const double xM = f.x_min + r * mrpt::round((double{x_max} - f.x_min) / r);
  const double yM = f.y_min + r * mrpt::round((double{y_max} - f.y_min) / r);
  const double zM = f.z_min + r * mrpt::round((double{z_max} - f.z_min) / r);
  const long sx = mrpt::round((xM - f.x_min) / r), sy = mrpt::round((yM - f.y_min) / r),
             sz = mrpt::round((zM - f.z_min) / r);
  if (sx <= 0 || sy <= 0 || sz <= 0) bad("holds no cell at this resolution");
  f.size_x = static_cast<std::uint32_t>(sx), f.size_y = static_cast<std::uint32_t>(sy),
  f.size_z = static_cast<std::uint32_t>(sz);
  // Every cell needs a lattice key (the map's resolution may differ from the float one by rounding).
  const auto inKeys = [&](double lo, std::uint32_t n) {
    const double k0 = std::round(lo / latticeResolution);
    return k0 >= kKeyMin && k0 + n - 1 <= kKeyMax;
  };
  if (!inKeys(f.x_min, f.size_x) || !inKeys(f.y_min, f.size_y) || !inKeys(f.z_min, f.size_z))
    bad("reaches beyond the key range of the lattice (2^21 cells per axis)");
  return f;
}

void checkFrame(const TGridFrame3D& f, double latticeResolution) {
  const auto sized = [&](double lo, std::uint32_t n) {
    if (!std::isfinite(lo) || n == 0 || n > (1u << kKeyBits)) return false;
    const double k0 = std::round(lo / latticeResolution);
    return k0 >= kKeyMin && k0 + n - 1 <= kKeyMax;
  };
  if (!(std::isfinite(f.resolution) && f.resolution > 0.0 &&
        std::abs(f.resolution - latticeResolution) <= 1e-6 * latticeResolution) ||
      !sized(f.x_min, f.size_x) || !sized(f.y_min, f.size_y) || !sized(f.z_min, f.size_z))
    throw std::runtime_error("rtog::CRTreeOccupancyGridMap: corrupt stream (3D grid geometry)");
}

Key keyOffset(const TGridFrame3D& f) {
  return Key{static_cast<std::int32_t>(std::lround(f.x_min / f.resolution)),
             static_cast<std::int32_t>(std::lround(f.y_min / f.resolution)),
             static_cast<std::int32_t>(std::lround(f.z_min / f.resolution))};
}

bool gridPoints(const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& robotPose, unsigned decimation3d,
                mrpt::maps::CPointsMap& pts, mrpt::math::TPoint3D& sensor) {
  if (const auto* o = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs)) {
    // COccupancyGridMap3D::internal_insertObservationScan2D's points.
    pts.insertionOptions.also_interpolate = false;
    pts.insertionOptions.addToExistingPointsMap = true;
    pts.insertionOptions.disableDeletion = true;
    pts.insertionOptions.fuseWithExisting = false;
    pts.insertionOptions.insertInvalidPoints = false;
    pts.insertionOptions.minDistBetweenLaserPoints = 0.0f;
    pts.loadFromRangeScan(*o, robotPose);
    sensor = mrpt::math::TPoint3D((robotPose + o->sensorPose).asTPose());
    return true;
  }
  if (const auto* o = dynamic_cast<const mrpt::obs::CObservation3DRangeScan*>(&obs)) {
    // internal_insertObservationScan3D's: unprojected in the sensor frame, then moved.
    o->load();
    mrpt::obs::T3DPointsProjectionParams pp;
    pp.takeIntoAccountSensorPoseOnRobot = false;
    pp.decimation = static_cast<std::uint8_t>(decimation3d);
    const_cast<mrpt::obs::CObservation3DRangeScan*>(o)->unprojectInto(pts, pp);
    const mrpt::poses::CPose3D sensorPose = robotPose + o->sensorPose;
    pts.changeCoordinatesReference(sensorPose);
    sensor = mrpt::math::TPoint3D(sensorPose.asTPose());
    return true;
  }
  return false;
}

bool traceRay(const TGridFrame3D& f, const Key& offset, const mrpt::math::TPoint3D& sensor,
              const mrpt::math::TPoint3D& end, std::vector<LayerStep>& out) {
  // COccupancyGridMap3D::insertRay, step for step.
  // An index beyond what the fixed point holds (the grid's int arithmetic would overflow) is
  // left out: no cell of the grid lies there.
  constexpr double kFar = double(1 << 21);
  bool far = false;
  const auto idx = [&](double v, double lo) {
    const double d = (v - lo) / f.resolution;
    if (!(d > -kFar && d < 2.0 * kFar)) {
      far = true;
      return 0;
    }
    return static_cast<int>(d);
  };
  int cx = idx(sensor.x, f.x_min), cy = idx(sensor.y, f.y_min), cz = idx(sensor.z, f.z_min);
  if (far || outside(f, cx, cy, cz)) return false;
  const int tx = idx(end.x, f.x_min), ty = idx(end.y, f.y_min), tz = idx(end.z, f.z_min);
  if (far) return false;
  const int ax = tx - cx, ay = ty - cy, az = tz - cz;
  const int n = std::max({std::abs(ax), std::abs(ay), std::abs(az)});
  if (n == 0) return true;  // the grid returns before the occupied step too
  const float inv = 1.0f / static_cast<float>(n);
  const auto inc = [inv](int a) { return (a < 0 ? -1 : +1) * mrpt::round((std::abs(a) << kFrBits) * inv); };
  const int fx = inc(ax), fy = inc(ay), fz = inc(az);
  // 64 bits: the grid's ints where they do not overflow, and defined where they would.
  std::int64_t px = std::int64_t{cx} << kFrBits, py = std::int64_t{cy} << kFrBits, pz = std::int64_t{cz} << kFrBits;
  const auto step = [&](int x, int y, int z, StepKind kind) {
    OccupancyMap::StepRun r{};
    r.x = x + offset.x, r.y = y + offset.y;
    r.count = 1;
    r.kind = kind;
    out.push_back(LayerStep{z + offset.z, r});
  };
  for (int k = 0; k < n; ++k) {
    step(cx, cy, cz, StepKind::Free);
    px += fx, py += fy, pz += fz;
    cx = static_cast<int>(px >> kFrBits), cy = static_cast<int>(py >> kFrBits), cz = static_cast<int>(pz >> kFrBits);
    if (outside(f, cx, cy, cz)) break;
  }
  if (!outside(f, tx, ty, tz)) step(tx, ty, tz, StepKind::Occupied);  // cellByIndex: nothing outside
  return true;
}

InsertStats insertPointCloud(OccupancyMap& map, const TGridFrame3D& f, const mrpt::math::TPoint3D& sensor,
                             const float* xs, const float* ys, const float* zs, std::size_t n, std::size_t decimation,
                             const StepRule& rule) {
  InsertStats stats;
  const Key offset = keyOffset(f);
  std::vector<LayerStep> steps;
  for (std::size_t i = 0; i < n; i += std::max<std::size_t>(decimation, 1)) {
    const std::size_t before = steps.size();
    if (!std::isfinite(xs[i]) || !std::isfinite(ys[i]) || !std::isfinite(zs[i])) {
      ++stats.skipped_non_finite;  // the grid would cast a NaN to an index: undefined, not followed
      continue;
    }
    if (!traceRay(f, offset, sensor, mrpt::math::TPoint3D(xs[i], ys[i], zs[i]), steps)) {
      ++stats.skipped_out_of_range;
      continue;
    }
    const bool hit = steps.size() > before && steps.back().run.kind == StepKind::Occupied;
    ++(hit ? stats.rays_hit : steps.size() > before ? stats.rays_truncated : stats.skipped_zero_length);
  }
  // Layer by layer, each in ray order: a cell's steps keep their order (cells are independent).
  std::stable_sort(steps.begin(), steps.end(), [](const LayerStep& a, const LayerStep& b) { return a.z < b.z; });
  std::vector<OccupancyMap::StepRun> runs;
  for (std::size_t i = 0; i < steps.size();) {
    std::size_t j = i;
    runs.clear();
    while (j < steps.size() && steps[j].z == steps[i].z) runs.push_back(steps[j++].run);
    stats += map.applyStepRuns(steps[i].z, runs.data(), runs.size(), rule);
    i = j;
  }
  return stats;
}

}  // namespace rtog::mrpt_grid3d
