// The estimator's graded models in the mrpt_grid preset: range noise (doc/range-noise.md) and
// pose blur (doc/pose-uncertainty.md) on the grids' own rasters and int8 cells: COccupancyGridMap2D's
// for 2D scans of a 2D section (insertGradedScan), COccupancyGridMap3D's in a 3D section
// (mrpt_grid3d::insertRays). Each graded change is rounded to the grid's units (gradedStep) and
// saturates as the grid does (stepCell). With sigma -> 0 and one pose a scan steps the grid's
// cells as the grid does, step for step (doc/mrpt_map.md has the rules).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <memory>
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
/// stops there). A band within half a stretch of the reading leaves the grid's own steps. The
/// cells from `first` on (those before are the caller's, e.g. bandStart()'s whole free steps), each
/// to out.push_back(CellStep) (a list, or PoseMixture's sink).
template <class CellAt, class Out>
void gradeBeam(const RangeNoiseRule& noise, double R, double sigma, std::uint32_t n, const Key* end,
               const Steps& whole, CellAt&& cellAt, Out& out, std::uint32_t first = 0) {
  const double s = R / n, reach = noise.reach(sigma);
  const auto graded = [&](const Key& k, float delta) {
    const auto [kind, size] = gradedStep(delta);
    if (size > 0) out.push_back(CellStep{k, kind, static_cast<std::uint8_t>(std::min(size, 127))});
  };
  float delta;
  Key k;
  for (std::uint32_t i = first; i < n; ++i) {
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

/// The raster cells of gradeBeam() wholly before the band (their whole free steps), of n.
inline std::uint32_t bandStart(const RangeNoiseRule& noise, double R, double sigma, std::uint32_t n) {
  // Cell i is before the band while (i + 1/2) R / n <= R - reach.
  const double before = std::floor((R - noise.reach(sigma)) * n / R + 0.5);
  return before <= 0.0 ? 0u : before >= n ? n : static_cast<std::uint32_t>(before);
}

/// The mixture of a scan's steps from several weighted poses (pose blur): a pose's change of a
/// cell is the sum of its steps there (as the grid would step it, one step per beam, saturation
/// aside), and each cell touched by any pose takes once the probability mixture
/// (rtog/core/mixture.hpp) of the poses' changes (a pose that did not touch it adds none),
/// rounded by gradedStep(): one step, which saturates as stepCell() does.
class PoseMixture {
 public:
  /// `box`, if given, holds every cell the poses will step (a 2D section's grid): the blocks are
  /// then found by a table over it (where that is no larger than kTableBlocks), else by hash.
  explicit PoseMixture(float prior, const Box* box = nullptr);
  ~PoseMixture();
  PoseMixture(const PoseMixture&) = delete;
  PoseMixture& operator=(const PoseMixture&) = delete;

  /// One pose's steps: `each(sink)` calls sink.push_back(CellStep) for each of them, in any order
  /// (the steps go straight into the cells' sums, not through a list).
  template <class Each>
  void add(double weight, Each&& each) {
    beginPose();
    Sink sink{*this};
    each(sink);
    endPose(weight);
  }
  /// Each touched cell's mixed step (none where it rounds to 0), block by block.
  void steps(std::vector<CellStep>& out) const;

  static constexpr std::size_t kTableBlocks = std::size_t{1} << 18;  // a 1 MiB table: 8192^2 cells of one layer
  static constexpr std::size_t kPoolBlocks = 1024;  // kept by a thread between scans: 3 MiB

 private:
  // Cells in blocks of 16 x 16 x 1 (a 2D layer's cells stay together), found once a block and
  // then by index: a pose's steps cost an add each. Beams walk on through one block for many
  // steps, so the block of the last step is kept and checked first, inline. The blocks come from
  // a pool the thread keeps (a scan's blur touches hundreds; fresh ones each scan cost a page
  // fault each).
  static constexpr int kCells = 256;
  struct Block {
    Key first;                                       // lattice key of its cell 0
    std::uint32_t stamp = 0;                         // the last pose that touched it
    std::array<std::int32_t, kCells> now{};          // that pose's change, in int8 units
    std::array<double, kCells> sum{};                // the mixture's sum (0 where not touched)
    std::array<std::uint64_t, kCells / 64> mine{}, touched{};
  };
  struct Sink {
    PoseMixture& m;
    void push_back(const CellStep& c) { m.step(c.key, c.kind == StepKind::Occupied ? -int{c.size} : int{c.size}); }
  };
  void step(const Key& k, int units) {
    auto x = static_cast<std::uint32_t>(k.x) - static_cast<std::uint32_t>(at_->first.x);
    auto y = static_cast<std::uint32_t>(k.y) - static_cast<std::uint32_t>(at_->first.y);
    if (x >= 16 || y >= 16 || k.z != at_->first.z) {
      enter(k);
      x = static_cast<std::uint32_t>(k.x - at_->first.x), y = static_cast<std::uint32_t>(k.y - at_->first.y);
    }
    const std::uint32_t i = y << 4 | x;
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    std::uint64_t& mine = at_->mine[i >> 6];
    if (!(mine & bit)) mine |= bit, at_->now[i] = 0;
    at_->now[i] += units;
  }
  /// Makes the block holding `k` the current one (made on first use, listed once a pose).
  void enter(const Key& k);
  void beginPose();
  void endPose(double weight);
  /// mix_.term(1, units / 16), from a table filled on demand.
  double unitTerm(int units) {
    const auto i = static_cast<std::size_t>(std::clamp(units, -kUnits, kUnits) + kUnits);
    const double t = unit_term_[i];
    return std::isnan(t) ? fillTerm(i) : t;
  }
  double fillTerm(std::size_t i);
  static std::vector<std::unique_ptr<Block>>& pool();  // the thread's spare blocks

  static constexpr int kUnits = 4096;  // changes beyond +-256 nats: the probability is 0 or 1 in double
  ProbabilityMixture mix_;
  std::vector<double> unit_term_;
  // Blocks by their block coordinates: a table over the box's (table_lo_, extents table_w_ x
  // table_h_ x table_d_; entry = position + 1, 0 none), else a hash.
  std::vector<std::uint32_t> table_;
  Key table_lo_{};
  std::uint32_t table_w_ = 0, table_h_ = 0, table_d_ = 0;
  detail::FlatHashMap64 index_;
  std::vector<std::unique_ptr<Block>> blocks_;  // in the order made
  std::vector<std::uint32_t> pose_blocks_;      // the blocks the current pose touched
  std::uint32_t stamp_ = 0;
  Block none_;        // the current block before a pose's first step: its key is no cell's
  Block* at_ = &none_;
};

/// `steps` into `cells` one after another (stepCell).
void applyInOrder(ScanCells& cells, const Key& offset, const std::vector<CellStep>& steps, const Steps& whole);

/// Inserts `scan` taken from the weighted `poses` (a certain pose: one of weight 1) into `map` in a
/// 2D section, growing `frame` as the grid grows to hold every pose's beams; each pose's beams on
/// COccupancyGridMap2D's raster (traceScan), range noise grading each hit beam's band
/// (sensorModel = rangeNoise; the band stops at the grid's border, which always lies 15 cells or
/// more past an end point), the poses mixed (PoseMixture); through the planar cache, as the
/// grid's own scans (the grid's runs in beam order, then graded cells grouped by kind and size).
/// `update`, if given, receives the runs stepped, each step's value after it and the rectangle
/// the grid grew to (for several poses, the grown grid's). One pose without range noise is
/// COccupancyGridMap2D's insertion (the preset's plain 2D scans take this path).
/// False (nothing changed) where the
/// grid would insert nothing from any pose (a pose it would not insert from adds no change);
/// otherwise `stats` counts the first such pose's beams and the cells written, `invalid` the
/// invalid ranges not taken as free. A throw leaves `map` and `frame` as they were.
bool insertGradedScan(OccupancyMap& map, TGridFrame2D& frame, const mrpt::obs::CObservation2DRangeScan& scan,
                      const std::vector<pose_sigma::SigmaPose>& poses,
                      const CRTreeOccupancyGridMap::TInsertionOptions& io, CRTreeOccupancyGridMap::GridScanUpdate* update,
                      InsertStats& stats, std::size_t& invalid);

}  // namespace rtog::mrpt_grid
