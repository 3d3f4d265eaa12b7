// The mrpt_grid preset: COccupancyGridMap2D's update of 2D range scans, reproduced so that an
// R-tree map holds exactly the cells the grid holds. Three parts of the grid decide its cells
// and are mirrored here type for type (float where MRPT computes in float): the int8 log-odds
// steps, the float geometry the grid grows to (it decides the cell a point falls in), and the
// fixed-point raster of its simple rays (MRPT 2.5: COccupancyGridMap2D_insert.cpp, _common.cpp).
// tests/mrpt/test_mrpt_grid_fidelity.cpp holds the result against the grid itself.
#pragma once

#include <cmath>

#include <cstdint>
#include <utility>
#include <vector>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::mrpt_grid {

/// The grid's steps in its int8 units (a cell holds the log-odds of being free, x16).
struct Steps {
  int free = 1, noecho = 1, occupied = 3;
};
Steps stepsOf(const CRTreeOccupancyGridMap::TInsertionOptions& o);
/// The steps as rtog stores them: value = -cell / 16, the natural log-odds of occupancy (every
/// int8 cell value is a float exactly).
StepRule stepRule(const Steps& s);
/// The clamp-and-add parameters with the same steps and the int8 bounds, for what the grid
/// does not rasterise beam by beam (3D observations).
LogOddsParams logOddsParams(const Steps& s, double occupiedThreshold);
inline float valueOfCell(int cell) { return static_cast<float>(-cell) / 16.0f; }
/// The int8 cell of a value of the preset (exact for values the preset makes).
int cellOfValue(float v);

/// A step of `size` int8 units of `kind` on a grid cell: a whole step of its kind under the
/// grid's own rule (updateCell_fast_free / _occupied: the cell steps unless it is within the
/// step of its bound, which it then takes; 127 - max(free, no-echo) is the free kinds' limit), a
/// smaller one (a graded change, or a cone's weighted step) saturating within itself of the bound.
/// A size of 0 leaves the cell as it was.
inline std::int8_t stepCell(std::int8_t c, StepKind kind, int size, const Steps& whole) {
  if (kind == StepKind::Occupied) {
    const int limit = -127 + size;
    return c > limit ? static_cast<std::int8_t>(c - size) : std::int8_t{-127};
  }
  const int whole_size = kind == StepKind::Free ? whole.free : whole.noecho;
  const int limit = size == whole_size ? 127 - std::max(whole.free, whole.noecho) : 127 - size;
  return c < limit ? static_cast<std::int8_t>(c + size) : std::int8_t{127};
}
/// The limit below which (in rtog's values, -cell / 16) a cell takes stepCell()'s step, as StepRule
/// holds it.
float stepLimit(StepKind kind, int size, const Steps& whole);
/// A graded change of the estimator's models (natural log-odds) as a step on the grid's int8
/// lattice: the nearest whole number of units (1/16; half away from zero), towards occupied for a
/// positive change. The rounding rule of every graded update of the preset (doc/mrpt_map.md;
/// InsertParams::graded_unit is the same rule where the core applies the change).
inline int gradedUnits(float delta) { return static_cast<int>(std::lround(16.0 * static_cast<double>(delta))); }
inline std::pair<StepKind, int> gradedStep(float delta) {
  const int units = gradedUnits(delta);
  return units > 0 ? std::pair<StepKind, int>{StepKind::Occupied, units}
                   : std::pair<StepKind, int>{StepKind::Free, -units};
}

/// COccupancyGridMap2D::setSize() and resizeGrid(..., additionalMargin = true), on the geometry.
void setSize(TGridFrame2D& f, float x_min, float x_max, float y_min, float y_max, float resolution);
void resize(TGridFrame2D& f, float x_min, float x_max, float y_min, float y_max);
inline int x2idx(const TGridFrame2D& f, float x) { return static_cast<int>((x - f.x_min) / f.resolution); }
inline int y2idx(const TGridFrame2D& f, float y) { return static_cast<int>((y - f.y_min) / f.resolution); }
/// Throws std::runtime_error unless `f` is a geometry setSize()/resize() could have made for a
/// map of `resolution` (a loaded map's frame): a finite ordered extent (checkGridExtent), the
/// map's resolution, sizes that match the extent, at most archive::kMaxGridCells cells. A
/// frame never set (a map first saved before format version 2: no cells, no layer) passes.
void checkFrame(const TGridFrame2D& f, double resolution);
/// Lattice key of the grid's cell 0 along x / y (the grid's minima lie on multiples of its resolution).
/// The frame's layer lies in a 2D view's height band [lo, hi] (its z-layers as bandRegion takes them).
inline bool layerInBand(const TGridFrame2D& f, double res, float lo, float hi) {
  return std::floor(lo / res) <= f.layer && f.layer <= std::floor(hi / res);
}
std::int32_t keyOffsetX(const TGridFrame2D& f);
std::int32_t keyOffsetY(const TGridFrame2D& f);

/// The rectangle the grid grows to (x_min, x_max, y_min, y_max) to hold points spanning
/// [x0, x1] x [y0, y1], as COccupancyGridMap2D grows for an observation; throws
/// std::out_of_range where it would reach beyond the key range.
void growRect(const TGridFrame2D& f, float x0, float x1, float y0, float y1, float grow[4]);

/// One scan's beams as the grid computes them before it grows to hold them.
struct ScanPlan {
  float px = 0, py = 0;            ///< sensor position
  std::vector<float> xs, ys;       ///< end point of each beam index used (others unset)
  float grow[4] = {0, 0, 0, 0};    ///< the rectangle the grid grows to: x_min, x_max, y_min, y_max
  std::size_t non_finite = 0;      ///< beams flagged valid whose range is NaN (skipped)
};
/// The grid's first half of inserting `o` taken at `robotPose`: false where the grid inserts
/// nothing (a scan that is not horizontal within horizontalTolerance, or off mapAltitude).
/// Throws std::invalid_argument for a non-finite pose.
bool planScan(const mrpt::obs::CObservation2DRangeScan& o, const mrpt::poses::CPose3D& robotPose,
              const CRTreeOccupancyGridMap::TInsertionOptions& opts, const TGridFrame2D& f, ScanPlan& plan);
/// The second half, on the grown geometry: the run of cells each beam steps, in the grid's order,
/// in lattice keys. Counts beams into `stats` as the core does.
/// The invalid ranges of `o` (every decimation-th) that the grid does not take as free space.
std::size_t invalidNotFree(const mrpt::obs::CObservation2DRangeScan& o, const CRTreeOccupancyGridMap::TInsertionOptions& opts);
/// `ranges`, if given, gets each run's reading (0 for a run without an end cell). A beam whose
/// cells surely miss `clip` (a restricted map's region, OccupancyMap::region(); empty: none) gives
/// no run, as the map would pass over every step of it; it is counted all the same.
void traceScan(const mrpt::obs::CObservation2DRangeScan& o, const ScanPlan& plan,
               const CRTreeOccupancyGridMap::TInsertionOptions& opts, const TGridFrame2D& f,
               std::vector<OccupancyMap::StepRun>& runs, InsertStats& stats, std::vector<float>* ranges = nullptr,
               const Box& clip = Box::empty());

}  // namespace rtog::mrpt_grid
