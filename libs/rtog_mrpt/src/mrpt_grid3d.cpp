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
#include "util/flat_hash_map.hpp"

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

/// One scan's cells while its rays step them, as the grid's int8 cells: blocks of 8^3 grid cells
/// made on first touch from the map's leaves there, so that a ray's steps cost an array update
/// (a block lookup each 8 cells or so) and a cell's steps stay in ray order; then written back.
class ScanCells {
 public:
  ScanCells(const OccupancyMap& map, const Key& offset) : map_(map), offset_(offset) {}

  std::int8_t& at(int cx, int cy, int cz) {
    const std::uint64_t key = std::uint64_t(unsigned(cx) >> kBits) | std::uint64_t(unsigned(cy) >> kBits) << 21 |
                              std::uint64_t(unsigned(cz) >> kBits) << 42;
    if (key != last_key_) {
      const auto next = static_cast<std::uint32_t>(blocks_.size());
      const std::uint32_t b = index_.findOrInsert(key, next);
      if (b == next) make(cx >> kBits, cy >> kBits, cz >> kBits);
      last_ = &blocks_[b];
      last_key_ = key;
    }
    const int i = ((cz & kMask) << (2 * kBits)) | ((cy & kMask) << kBits) | (cx & kMask);
    last_->seen[i >> 6] |= std::uint64_t{1} << (i & 63);
    return last_->v[i];
  }

  /// The cells stepped, in lattice keys with their values: greedy boxes of equal cells within a
  /// block (x runs grown along y, then z), so that a brick first made by this scan does not hold
  /// a leaf per cell (assignCells takes a new brick's boxes as its leaves).
  void emit(std::vector<Box>& boxes, std::vector<float>& values) const {
    for (const Block& b : blocks_) {
      std::array<std::uint64_t, kCells / 64> open = b.seen;  // stepped, not yet in a box
      const auto isOpen = [&](int i) { return ((open[static_cast<std::size_t>(i) >> 6] >> (i & 63)) & 1u) != 0; };
      const auto at = [](int x, int y, int z) { return (z << (2 * kBits)) | (y << kBits) | x; };
      for (int i = 0; i < kCells; ++i) {
        if (!isOpen(i)) continue;
        const int x0 = i & kMask, y0 = (i >> kBits) & kMask, z0 = i >> (2 * kBits);
        const std::int8_t v = b.v[static_cast<std::size_t>(i)];
        const auto same = [&](int x, int y, int z) { return isOpen(at(x, y, z)) && b.v[static_cast<std::size_t>(at(x, y, z))] == v; };
        int x1 = x0, y1 = y0, z1 = z0;
        while (x1 + 1 < kSide && same(x1 + 1, y0, z0)) ++x1;
        const auto rowSame = [&](int y, int z) {
          for (int x = x0; x <= x1; ++x)
            if (!same(x, y, z)) return false;
          return true;
        };
        while (y1 + 1 < kSide && rowSame(y1 + 1, z0)) ++y1;
        const auto sliceSame = [&](int z) {
          for (int y = y0; y <= y1; ++y)
            if (!rowSame(y, z)) return false;
          return true;
        };
        while (z1 + 1 < kSide && sliceSame(z1 + 1)) ++z1;
        for (int z = z0; z <= z1; ++z)
          for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
              const int c = at(x, y, z);
              open[static_cast<std::size_t>(c) >> 6] &= ~(std::uint64_t{1} << (c & 63));
            }
        boxes.push_back(Box{Key{b.x0 + x0, b.y0 + y0, b.z0 + z0}, Key{b.x0 + x1, b.y0 + y1, b.z0 + z1}});
        values.push_back(mrpt_grid::valueOfCell(v));
      }
    }
  }

 private:
  static constexpr int kBits = 3, kSide = 1 << kBits, kMask = kSide - 1, kCells = kSide * kSide * kSide;
  struct Block {
    std::int32_t x0, y0, z0;  // lattice key of its first cell
    std::array<std::int8_t, kCells> v;
    std::array<std::uint64_t, kCells / 64> seen;
  };
  void make(int bx, int by, int bz) {
    Block& b = blocks_.emplace_back();
    b.x0 = offset_.x + bx * kSide, b.y0 = offset_.y + by * kSide, b.z0 = offset_.z + bz * kSide;
    b.v.fill(0);  // unknown: the grid's 0.5
    b.seen.fill(0);
    last_key_ = ~std::uint64_t{0};  // emplace_back may have moved the blocks
    const Box region{Key{b.x0, b.y0, b.z0}, Key{b.x0 + kMask, b.y0 + kMask, b.z0 + kMask}};
    map_.forEachLeafIn(region, [&](const Box& leaf, float value) {
      const auto c = static_cast<std::int8_t>(mrpt_grid::cellOfValue(value));
      for (std::int32_t z = std::max(leaf.min.z, region.min.z); z <= std::min(leaf.max.z, region.max.z); ++z)
        for (std::int32_t y = std::max(leaf.min.y, region.min.y); y <= std::min(leaf.max.y, region.max.y); ++y)
          for (std::int32_t x = std::max(leaf.min.x, region.min.x); x <= std::min(leaf.max.x, region.max.x); ++x)
            b.v[static_cast<std::size_t>(((z - b.z0) << (2 * kBits)) | ((y - b.y0) << kBits) | (x - b.x0))] = c;
    });
  }

  const OccupancyMap& map_;
  Key offset_;
  std::vector<Block> blocks_;
  detail::FlatHashMap64 index_;
  std::uint64_t last_key_ = ~std::uint64_t{0};
  Block* last_ = nullptr;
};

enum class Ray { Traced, SensorOutside, Zero };

/// COccupancyGridMap3D::insertRay, step for step: visit(cx, cy, cz, occupied) for each step.
template <class Visit>
Ray traceRay(const TGridFrame3D& f, const mrpt::math::TPoint3D& sensor, const mrpt::math::TPoint3D& end,
             Visit&& visit) {
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
  if (far || outside(f, cx, cy, cz)) return Ray::SensorOutside;
  const int tx = idx(end.x, f.x_min), ty = idx(end.y, f.y_min), tz = idx(end.z, f.z_min);
  if (far) return Ray::SensorOutside;
  const int ax = tx - cx, ay = ty - cy, az = tz - cz;
  const int n = std::max({std::abs(ax), std::abs(ay), std::abs(az)});
  if (n == 0) return Ray::Zero;  // the grid returns before the occupied step too
  const float inv = 1.0f / static_cast<float>(n);
  const auto inc = [inv](int a) { return (a < 0 ? -1 : +1) * mrpt::round((std::abs(a) << kFrBits) * inv); };
  const int fx = inc(ax), fy = inc(ay), fz = inc(az);
  // 64 bits: the grid's ints where they do not overflow, and defined where they would.
  std::int64_t px = std::int64_t{cx} << kFrBits, py = std::int64_t{cy} << kFrBits, pz = std::int64_t{cz} << kFrBits;
  for (int k = 0; k < n; ++k) {
    visit(cx, cy, cz, false);
    px += fx, py += fy, pz += fz;
    cx = static_cast<int>(px >> kFrBits), cy = static_cast<int>(py >> kFrBits), cz = static_cast<int>(pz >> kFrBits);
    if (outside(f, cx, cy, cz)) break;
  }
  if (!outside(f, tx, ty, tz)) visit(tx, ty, tz, true);  // cellByIndex: nothing outside
  return Ray::Traced;
}

}  // namespace

Steps3D stepsOf(const CRTreeOccupancyGridMap::TInsertionOptions& io) {
  const mrpt_grid::Steps s = mrpt_grid::stepsOf(io);
  return Steps3D{s.free, s.occupied};
}

InsertStats insertRays(OccupancyMap& map, const TGridFrame3D& f, const mrpt::math::TPoint3D& sensor, std::size_t n,
                       const std::function<mrpt::math::TPoint3D(std::size_t)>& endOf, const Steps3D& steps) {
  InsertStats stats;
  ScanCells cells(map, keyOffset(f));
  // updateCell_fast_free / _occupied, in the grid's int8 arithmetic.
  const int free_limit = 127 - steps.free, occupied_limit = -127 + steps.occupied;
  const auto step = [&](int cx, int cy, int cz, bool occupied) {
    std::int8_t& c = cells.at(cx, cy, cz);
    if (occupied)
      c = c > occupied_limit ? static_cast<std::int8_t>(c - steps.occupied) : std::int8_t{-127};
    else
      c = c < free_limit ? static_cast<std::int8_t>(c + steps.free) : std::int8_t{127};
  };
  for (std::size_t i = 0; i < n; ++i) {
    const mrpt::math::TPoint3D e = endOf(i);
    if (!std::isfinite(e.x) || !std::isfinite(e.y) || !std::isfinite(e.z)) {
      ++stats.skipped_non_finite;  // the grid would cast a NaN to an index: undefined, not followed
      continue;
    }
    switch (traceRay(f, sensor, e, step)) {
      case Ray::Traced: ++stats.rays_hit; break;
      case Ray::SensorOutside: ++stats.skipped_out_of_range; break;
      case Ray::Zero: ++stats.skipped_zero_length; break;
    }
  }
  std::vector<Box> boxes;
  std::vector<float> values;
  cells.emit(boxes, values);
  if (!boxes.empty()) {
    const InsertStats assigned = map.assignCells(boxes.data(), values.data(), boxes.size());
    stats.cells_free = assigned.cells_free, stats.cells_occupied = assigned.cells_occupied;
    stats.leaves_created = assigned.leaves_created, stats.leaves_merged = assigned.leaves_merged;
  }
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
