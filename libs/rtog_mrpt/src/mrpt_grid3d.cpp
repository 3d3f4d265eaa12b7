// The mrpt_grid preset in 3D (mrpt_grid3d.hpp). Built with -ffp-contract=off, as mrpt_grid.cpp:
// the grid's arithmetic has no fused multiply-add.
#include "mrpt_grid3d.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include <mrpt/core/round.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/T3DPointsProjectionParams.h>
#include <mrpt/system/string_utils.h>

#include "mrpt_grid.hpp"
#include "options_check.hpp"
#include "grid_cells.hpp"
#include "grid_graded.hpp"

namespace rtog::mrpt_grid3d {

namespace {
constexpr int kFrBits = 9;  // the grid's fixed-point bits (FRBITS)

bool outside(const TGridFrame3D& f, int cx, int cy, int cz) {
  return cx < 0 || cx >= static_cast<int>(f.size_x) || cy < 0 || cy >= static_cast<int>(f.size_y) || cz < 0 ||
         cz >= static_cast<int>(f.size_z);
}
}  // namespace

TGridFrame3D makeFrame(float x_min, float x_max, float y_min, float y_max, float z_min, float z_max, float resolution,
                       double latticeResolution) {
  const auto bad = [](const std::string& why) {
    throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: the 3D grid extent " + why);
  };
  if (!(std::isfinite(x_min) && std::isfinite(x_max) && x_min < x_max && std::isfinite(y_min) &&
        std::isfinite(y_max) && y_min < y_max && std::isfinite(z_min) && std::isfinite(z_max) && z_min < z_max))
    bad("needs finite min < max along x, y and z");
  if (!(std::isfinite(resolution) && resolution > 0.0f)) bad("needs a positive resolution");
  // More cells along an axis than the lattice has keys: refused before any count is rounded.
  constexpr double kMostCells = double(1 << kKeyBits);
  if (!((double{x_max} - x_min) / resolution < kMostCells && (double{y_max} - y_min) / resolution < kMostCells &&
        (double{z_max} - z_min) / resolution < kMostCells))
    bad("reaches beyond the key range of the lattice (2^21 cells per axis)");
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
    // internal_insertObservationScan3D's: unprojected in the sensor frame, then moved. One that
    // holds only its points the grid would drop without a word: left to the caller's points.
    o->load();
    if (!o->hasRangeImage) return false;
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

namespace {

enum class Ray { Traced, SensorOutside, Zero };

/// COccupancyGridMap3D::insertRay's raster of a ray: n steps from the sensor's cell c by the
/// fixed-point increments f, then the end's cell t.
struct Raster {
  int cx, cy, cz, tx, ty, tz, n;
  std::int64_t fx, fy, fz;
  /// Raster cell i (i < n: the i-th free step; beyond, the raster continued), false outside the grid.
  bool cell(const TGridFrame3D& f, std::int64_t i, int& x, int& y, int& z) const {
    x = static_cast<int>(((std::int64_t{cx} << kFrBits) + i * fx) >> kFrBits);
    y = static_cast<int>(((std::int64_t{cy} << kFrBits) + i * fy) >> kFrBits);
    z = static_cast<int>(((std::int64_t{cz} << kFrBits) + i * fz) >> kFrBits);
    return !outside(f, x, y, z);
  }
};

Ray rasterOf(const TGridFrame3D& f, const mrpt::math::TPoint3D& sensor, const mrpt::math::TPoint3D& end, Raster& r) {
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
  r.cx = idx(sensor.x, f.x_min), r.cy = idx(sensor.y, f.y_min), r.cz = idx(sensor.z, f.z_min);
  if (far || outside(f, r.cx, r.cy, r.cz)) return Ray::SensorOutside;
  r.tx = idx(end.x, f.x_min), r.ty = idx(end.y, f.y_min), r.tz = idx(end.z, f.z_min);
  if (far) return Ray::SensorOutside;
  const int ax = r.tx - r.cx, ay = r.ty - r.cy, az = r.tz - r.cz;
  r.n = std::max({std::abs(ax), std::abs(ay), std::abs(az)});
  if (r.n == 0) return Ray::Zero;  // the grid returns before the occupied step too
  const float inv = 1.0f / static_cast<float>(r.n);
  const auto inc = [inv](int a) { return (a < 0 ? -1 : +1) * mrpt::round((std::abs(a) << kFrBits) * inv); };
  r.fx = inc(ax), r.fy = inc(ay), r.fz = inc(az);
  return Ray::Traced;
}

/// COccupancyGridMap3D::insertRay, step for step: visit(cx, cy, cz, occupied) for each step (the
/// free steps stop where the raster leaves the grid; the end's cell only inside it).
template <class Visit>
void walk(const TGridFrame3D& f, const Raster& r, Visit&& visit) {
  // 64 bits: the grid's ints where they do not overflow, and defined where they would.
  std::int64_t px = std::int64_t{r.cx} << kFrBits, py = std::int64_t{r.cy} << kFrBits, pz = std::int64_t{r.cz} << kFrBits;
  int cx = r.cx, cy = r.cy, cz = r.cz;
  for (int k = 0; k < r.n; ++k) {
    visit(cx, cy, cz, false);
    px += r.fx, py += r.fy, pz += r.fz;
    cx = static_cast<int>(px >> kFrBits), cy = static_cast<int>(py >> kFrBits), cz = static_cast<int>(pz >> kFrBits);
    if (outside(f, cx, cy, cz)) break;
  }
  if (!outside(f, r.tx, r.ty, r.tz)) visit(r.tx, r.ty, r.tz, true);  // cellByIndex: nothing outside
}

/// Counts a ray into `stats`; true if it is traced.
bool countRay(const mrpt::math::TPoint3D& e, Ray ray, InsertStats& stats) {
  if (!std::isfinite(e.x) || !std::isfinite(e.y) || !std::isfinite(e.z)) {
    ++stats.skipped_non_finite;  // the grid would cast a NaN to an index: undefined, not followed
    return false;
  }
  switch (ray) {
    case Ray::Traced: ++stats.rays_hit; return true;
    case Ray::SensorOutside: ++stats.skipped_out_of_range; return false;
    case Ray::Zero: ++stats.skipped_zero_length; return false;
  }
  return false;
}

/// One ray set's steps to out.push_back(CellStep), ray by ray: the grid's, or graded by
/// gradeBeam() with range noise.
template <class Out>
void setSteps(const TGridFrame3D& f, const RaySet& set, const mrpt_grid::Steps& whole, const RangeNoiseRule* noise,
              Out& out, InsertStats& stats) {
  const Key o = keyOffset(f);
  const auto key = [&](int x, int y, int z) { return Key{o.x + x, o.y + y, o.z + z}; };
  for (std::size_t i = 0; i < set.n; ++i) {
    const mrpt::math::TPoint3D e = set.endOf(i);
    Raster r{};
    const bool finite = std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z);
    if (!countRay(e, finite ? rasterOf(f, set.sensor, e, r) : Ray::Zero, stats)) continue;
    const double R = std::sqrt(mrpt::square(e.x - set.sensor.x) + mrpt::square(e.y - set.sensor.y) +
                               mrpt::square(e.z - set.sensor.z));
    const double sigma = noise ? noise->sigma(R) : 0.0;
    if (!(sigma > 0.0)) {
      walk(f, r, [&](int x, int y, int z, bool occupied) {
        out.push_back(occupied ? mrpt_grid::CellStep{key(x, y, z), StepKind::Occupied, static_cast<std::uint8_t>(whole.occupied)}
                               : mrpt_grid::CellStep{key(x, y, z), StepKind::Free, static_cast<std::uint8_t>(whole.free)});
      });
      continue;
    }
    const Key end = key(r.tx, r.ty, r.tz);
    mrpt_grid::gradeBeam(*noise, R, sigma, static_cast<std::uint32_t>(r.n), outside(f, r.tx, r.ty, r.tz) ? nullptr : &end,
                         whole, [&](std::uint32_t k, Key& out_key) {
                           int x, y, z;
                           if (!r.cell(f, k, x, y, z)) return false;
                           out_key = key(x, y, z);
                           return true;
                         }, out);
  }
}

}  // namespace

Steps3D stepsOf(const CRTreeOccupancyGridMap::TInsertionOptions& io) {
  const mrpt_grid::Steps s = mrpt_grid::stepsOf(io);
  return Steps3D{s.free, s.occupied};
}

InsertStats insertRays(OccupancyMap& map, const TGridFrame3D& f, const std::vector<RaySet>& sets, const Steps3D& steps,
                       const RangeNoiseRule* noise) {
  InsertStats stats;
  // updateCell_fast_free / _occupied, in the grid's int8 arithmetic (no no-return beams: the
  // free limit is 127 - free).
  const mrpt_grid::Steps whole{steps.free, steps.free, steps.occupied};
  if (sets.size() == 1 && !noise) {  // the grid's own insertion: each step as it is traced
    const RaySet& set = sets.front();
    mrpt_grid::ScanCells cells(map, keyOffset(f));
    const auto step = [&](int cx, int cy, int cz, bool occupied) {
      std::int8_t& c = cells.at(cx, cy, cz);
      c = occupied ? mrpt_grid::stepCell(c, StepKind::Occupied, whole.occupied, whole)
                   : mrpt_grid::stepCell(c, StepKind::Free, whole.free, whole);
    };
    for (std::size_t i = 0; i < set.n; ++i) {
      const mrpt::math::TPoint3D e = set.endOf(i);
      Raster r{};
      const bool finite = std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z);
      if (countRay(e, finite ? rasterOf(f, set.sensor, e, r) : Ray::Zero, stats)) walk(f, r, step);
    }
    const InsertStats assigned = cells.writeBack(map);
    stats.cells_free = assigned.cells_free, stats.cells_occupied = assigned.cells_occupied;
    stats.leaves_created = assigned.leaves_created, stats.leaves_merged = assigned.leaves_merged;
    return stats;
  }
  // One set with range noise: its steps in order; several: their mixture, a step a cell.
  std::vector<mrpt_grid::CellStep> cellSteps;
  if (sets.size() == 1) {
    setSteps(f, sets.front(), whole, noise, cellSteps, stats);
  } else {
    const Key o = keyOffset(f);
    const Box grid{o, Key{o.x + static_cast<std::int32_t>(f.size_x) - 1, o.y + static_cast<std::int32_t>(f.size_y) - 1,
                          o.z + static_cast<std::int32_t>(f.size_z) - 1}};
    mrpt_grid::PoseMixture mixture(map.logOddsModel().prior(), &grid);
    for (std::size_t s = 0; s < sets.size(); ++s) {
      InsertStats own;
      mixture.add(sets[s].weight, [&](auto& sink) { setSteps(f, sets[s], whole, noise, sink, own); });
      if (s == 0) stats = own;
    }
    mixture.steps(cellSteps);
  }
  const Key origin{kKeyMin, kKeyMin, kKeyMin};
  mrpt_grid::ScanCells cells(map, origin);
  mrpt_grid::applyInOrder(cells, origin, cellSteps, whole);
  const InsertStats assigned = cells.writeBack(map);
  stats.cells_free = assigned.cells_free, stats.cells_occupied = assigned.cells_occupied;
  stats.leaves_created = assigned.leaves_created, stats.leaves_merged = assigned.leaves_merged;
  return stats;
}

void readSectionKeys(const mrpt::config::CConfigFileBase& source, const std::string& prefix,
                     CRTreeOccupancyGridMap::TInsertionOptions& io, CRTreeOccupancyGridMap::TLikelihoodOptions& lo) {
  // COccupancyGridMap3D numbers its two methods 0 and 1 (names read as in every section).
  const std::string lsec = prefix + "_likelihoodOpts";
  const std::string m = mrpt::system::trim(source.read_string(lsec, "likelihoodMethod", ""));
  if (!m.empty() && m.find_first_not_of("0123456789") == std::string::npos) {
    if (m != "0" && m != "1")
      throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: invalid option [" + lsec +
                                  "] likelihoodMethod: a 3D section numbers COccupancyGridMap3D's methods, 0 "
                                  "(lmLikelihoodField_Thrun) or 1 (lmRayTracing), got " + m);
    lo.likelihoodMethod = m == "0" ? CRTreeOccupancyGridMap::lmLikelihoodField_Thrun : CRTreeOccupancyGridMap::lmRayTracing;
  }
  // MRPT 2.5.8's COccupancyGridMap3D does not read decimation_3d_range: its depth images keep 8.
  const std::string isec = prefix + "_insertOpts";
  if (source.keyExists(isec, "decimation_3d_range"))
    reportInertKey(isec, "decimation_3d_range",
                   "in a 3D section depth images are decimated by 8, as COccupancyGridMap3D (MRPT 2.5.8) does not "
                   "read this key");
  io.decimation_3d_range = 8;
}

}  // namespace rtog::mrpt_grid3d
