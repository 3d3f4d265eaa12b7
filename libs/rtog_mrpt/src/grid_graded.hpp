// The estimator's graded models in the mrpt_grid preset: range noise (doc/range-noise.md) and
// pose blur (doc/pose-uncertainty.md) on the grids' own rasters and int8 cells: COccupancyGridMap2D's
// for 2D scans of a 2D section (insertGradedScan), COccupancyGridMap3D's in a 3D section
// (mrpt_grid3d::insertRays). Each graded change is rounded to the grid's units (gradedStep) and
// saturates as the grid does (stepCell). With sigma -> 0 and one pose a scan steps the grid's
// cells as the grid does, step for step (doc/mrpt_map.md has the rules).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "grid_cells.hpp"
#include "mrpt_grid.hpp"
#include "pose_sigma.hpp"
#include "rtog/core/mixture.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/range_noise.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "util/flat_hash_map.hpp"

namespace rtog::mrpt_grid {

/// One step of one cell, in the grid's int8 units.
struct CellStep {
  Key key;
  StepKind kind;
  std::uint8_t size;
};

/// The steps of one hit beam of reading `R` with range noise of `sigma` > 0 on a grid's raster of
/// `n` > 0 steps from the sensor's cell to the end cell. The raster's cells stand for equal
/// stretches of the beam: cell i (cellAt(i, key), i < n) covers [(i - 1/2), (i + 1/2)] R / n, the
/// end cell (`end`; nullptr where it lies outside the grid) the stretch about the reading, and the
/// raster goes on past the end cell with the same increments (cellAt(i), i > n) to the band's far
/// edge. Each cell takes RangeNoiseRule's change rounded by gradedStep(); cells wholly before the
/// band take the whole free step. cellAt returns false where the raster leaves the grid (the beam
/// stops there). A band within half a stretch of the reading leaves the grid's own steps.
template <class CellAt>
void gradeBeam(const RangeNoiseRule& noise, double R, double sigma, std::uint32_t n, const Key* end,
               const Steps& whole, CellAt&& cellAt, std::vector<CellStep>& out) {
  const double s = R / n, reach = noise.reach(sigma);
  const auto graded = [&](const Key& k, float delta) {
    const auto [kind, size] = gradedStep(delta);
    if (size > 0) out.push_back(CellStep{k, kind, static_cast<std::uint8_t>(std::min(size, 127))});
  };
  float delta;
  Key k;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (!cellAt(i, k)) break;
    const double hi = (i + 0.5) * s;
    if (hi <= R - reach)
      out.push_back(CellStep{k, StepKind::Free, static_cast<std::uint8_t>(whole.free)});
    else if (noise.cellDelta(std::max(0.0, (i - 0.5) * s), std::min(hi, R), R, sigma, delta))
      graded(k, delta);
  }
  if (!end) return;
  if (noise.cellDelta(std::max(0.0, R - 0.5 * s), R + 0.5 * s, R, sigma, delta)) graded(*end, delta);
  for (std::uint32_t i = n + 1; (i - 0.5) * s < R + reach; ++i) {
    if (!cellAt(i, k)) break;
    if (k == *end) continue;
    if (!noise.cellDelta((i - 0.5) * s, (i + 0.5) * s, R, sigma, delta)) break;
    graded(k, delta);
  }
}

/// A scan's steps from one or several weighted poses onto the map's cells. One pose: its steps
/// step the cells in order, as the grid would. Several: each pose's steps are taken on its own
/// copy of the cells as they were before the scan, and each cell touched by any pose then takes
/// once the probability mixture (rtog/core/mixture.hpp) of the poses' net changes (a pose that
/// did not touch it adds none), rounded to the grid's units and kept within +-127.
class PoseMixture {
 public:
  PoseMixture(const OccupancyMap& map, const Steps& whole, std::size_t poses)
      : cells_(map, Key{kKeyMin, kKeyMin, kKeyMin}), whole_(whole), several_(poses > 1), mix_(map.logOddsModel().prior()) {}

  void add(double weight, const std::vector<CellStep>& steps);
  /// The cells written back into the map (OccupancyMap::assignCells).
  InsertStats writeBack(OccupancyMap& map);

 private:
  std::int8_t& at(const Key& k) { return cells_.at(k.x - kKeyMin, k.y - kKeyMin, k.z - kKeyMin); }
  std::int8_t peek(const Key& k) { return cells_.peek(k.x - kKeyMin, k.y - kKeyMin, k.z - kKeyMin); }

  ScanCells cells_;
  Steps whole_;
  bool several_;
  ProbabilityMixture mix_;
  detail::FlatHashMap64 index_, own_;             // packed key -> position in sums_ / now_
  std::vector<std::pair<Key, double>> sums_;      // the mixture's sum per cell
  std::vector<std::pair<Key, std::int8_t>> now_;  // one pose's cells after its steps
};

/// Inserts `scan` taken from the weighted `poses` (a certain pose: one of weight 1) into `map` in a
/// 2D section, growing `frame` as the grid grows to hold every pose's beams; each pose's beams on
/// COccupancyGridMap2D's raster (traceScan), range noise grading each hit beam's band
/// (sensorModel = rangeNoise; the band stops at the grid's border, which always lies 15 cells or
/// more past an end point), the poses mixed (PoseMixture). False (nothing changed) where the
/// grid would insert nothing from any pose (a pose it would not insert from adds no change);
/// otherwise `stats` counts the first such pose's beams and the cells written, `invalid` the
/// invalid ranges not taken as free. A throw leaves `map` and `frame` as they were.
bool insertGradedScan(OccupancyMap& map, TGridFrame2D& frame, const mrpt::obs::CObservation2DRangeScan& scan,
                      const std::vector<pose_sigma::SigmaPose>& poses,
                      const CRTreeOccupancyGridMap::TInsertionOptions& io, InsertStats& stats, std::size_t& invalid);

}  // namespace rtog::mrpt_grid
