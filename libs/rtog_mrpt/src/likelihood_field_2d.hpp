// Private to librtog_mrpt: the likelihood field (lmLikelihoodField_Thrun) of a planar scan on
// a 2D grid of MRPT cells, each cell's term computed once and kept. The value is
// COccupancyGridMap2D::computeObservationLikelihood's for the same cells, scan and pose, bit for
// bit (tested); what it saves is the sine and cosine of the pose and the logarithm of the term
// that the stock grid computes again for every point. One rule for two kinds of cells: the dense
// 2D view (a COccupancyGridMap2D) and the copy-on-write tiles particles share (grid_tiles.hpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

namespace rtog {

/// The field's occupied cells: those below this (P(occupied) > 0.5), as the stock grid's.
float occupiedBelow();

/// The field's constants in the precision the stock grid computes them in (floats where its
/// options are floats), so that every term is the same number.
struct FieldConstants {
  FieldConstants(const mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions& o, double resolution);
  float zRandomTerm, zHit, q;  // q = -1 / (2 stdHit^2)
  double maxCorrDistSq;         // a float square, widened
  double unitsPerSqMetre;       // squared distances counted in (cell / 10)^2
  unsigned capUnits;            // the search's cap in those units
  int window;                   // cells searched either side
  bool squareDist;
  bool operator==(const FieldConstants& o) const {
    return zRandomTerm == o.zRandomTerm && zHit == o.zHit && q == o.q && maxCorrDistSq == o.maxCorrDistSq &&
           unitsPerSqMetre == o.unitsPerSqMetre && capUnits == o.capUnits && window == o.window &&
           squareDist == o.squareDist;
  }
  /// The mixture at squared distance `best` (in units) to the nearest occupied cell.
  double termOfBest(unsigned best) const {
    float dist = static_cast<float>(best * (1.0 / unitsPerSqMetre));
    if (squareDist) dist *= dist;
    return zRandomTerm + zHit * std::exp(q * dist);  // in floats, as the stock grid
  }
  /// The squared distance (units, capped) of the nearest occupied cell in the window about
  /// (cx, cy), clipped to [0, sx) x [0, sy); row(y, x0, x1, visit) calls visit(x) for each
  /// occupied cell x0..x1 of row y.
  template <class Row>
  unsigned bestAt(int cx, int cy, int sx, int sy, Row&& row) const {
    const int x0 = std::max(0, cx - window), x1 = std::min(sx - 1, cx + window);
    const int y0 = std::max(0, cy - window), y1 = std::min(sy - 1, cy + window);
    unsigned best = capUnits;
    for (int y = y0; y <= y1; ++y) {
      const auto dy = static_cast<unsigned>(10 * (y - cy));
      const unsigned dy2 = dy * dy;
      row(y, x0, x1, [&](int x) {
        const auto dx = static_cast<unsigned>(10 * (x - cx));  // squared modulo 2^32: the same
        best = std::min(best, dx * dx + dy2);
      });
    }
    return best;
  }
};

/// What the field reads of a grid besides its cells.
struct FieldGrid {
  const mrpt::maps::COccupancyGridMap2D::TInsertionOptions* insertion;
  const mrpt::maps::COccupancyGridMap2D::TLikelihoodOptions* likelihood;
  float resolution, x_min, y_min;
  unsigned size_x, size_y;
};

/// What the field's sum over a scan's points needs, prepared once per scan and pose.
struct FieldScan {
  double decided;  ///< the result when no point is scored (-10, -100), else NaN
  const float *xs, *ys;
  std::size_t n, step;
  double x, y, s, c;  ///< the pose and the sine and cosine of its heading
  bool logs;
  double outside_value;
};
FieldScan prepareFieldScan(const FieldGrid& g, const FieldConstants& f, const mrpt::obs::CObservation2DRangeScan& scan,
                           const mrpt::poses::CPose3D& pose);

/// COccupancyGridMap2D::x2idx / y2idx, without its float-to-int cast of a point beyond the int
/// range (undefined behaviour): such a point is outside the grid, -1, as x86 turns the cast into
/// INT_MIN, which the stock grid then counts outside too.
inline int fieldCellIndex(double v, double lo, double res) {
  const double i = (v - lo) / res;
  return i > -2147483648.0 && i < 2147483647.0 ? static_cast<int>(i) : -1;
}

/// The log-likelihood of `scan` from `pose` on grid `g` (lmLikelihoodField_Thrun; `f` its
/// constants), with value(cx, cy, logs) giving a cell's log term (its term if !logs) for cells
/// inside the border.
template <class Value>
double fieldScanLogLikelihood(const FieldGrid& g, const FieldConstants& f, const mrpt::obs::CObservation2DRangeScan& scan,
                              const mrpt::poses::CPose3D& pose, Value&& value) {
  const FieldScan p = prepareFieldScan(g, f, scan, pose);
  if (!std::isnan(p.decided)) return p.decided;
  const unsigned last_x = g.size_x - 1, last_y = g.size_y - 1;
  double sum = 0;
  std::size_t m = 0;
  for (std::size_t j = 0; j < p.n; j += p.step, ++m) {
    const double lx = p.xs[j], ly = p.ys[j];
    const int cx = fieldCellIndex(p.x + lx * p.c - ly * p.s, g.x_min, g.resolution);
    const int cy = fieldCellIndex(p.y + lx * p.s + ly * p.c, g.y_min, g.resolution);
    // The grid's last row and column count as outside, as in the stock grid.
    if (static_cast<unsigned>(cx) >= last_x || static_cast<unsigned>(cy) >= last_y) {
      sum += p.outside_value;
      continue;
    }
    sum += value(cx, cy, p.logs);
  }
  return p.logs ? sum : std::log(sum / static_cast<double>(m));
}

/// As LikelihoodField2D::scanLogLikelihood, with the terms kept in the grid's own cache
/// (COccupancyGridMap2D's precomputed field `kept`, its flag `outdated`, its mark of a term not
/// computed) as MRPT's computeLikelihoodField_Thrun keeps them: the grid's methods and this one
/// share it, and whatever marks it outdated (MRPT's own resizing) holds for both.
double keptFieldScanLogLikelihood(const mrpt::maps::COccupancyGridMap2D& grid, std::vector<double>& kept,
                                  bool& outdated, const mrpt::obs::CObservation2DRangeScan& scan,
                                  const mrpt::poses::CPose3D& pose);
/// MRPT's mark of a kept term not computed (LIK_LF_CACHE_INVALID).
constexpr double kTermNotComputed = 66;

class LikelihoodField2D {
 public:
  /// Forgets every kept term (the grid's cells or the field's options changed).
  void clear() {
    pages_.clear();
    cells_ = 0;
  }
  /// The log-likelihood of `scan` taken from `pose` on `grid` by its likelihoodOptions
  /// (lmLikelihoodField_Thrun), as grid.computeObservationLikelihood() gives it. Keeps the terms
  /// if the grid's enableLikelihoodCache is on.
  double scanLogLikelihood(const mrpt::maps::COccupancyGridMap2D& grid, const mrpt::obs::CObservation2DRangeScan& scan,
                           const mrpt::poses::CPose3D& pose);

 private:
  static constexpr unsigned kPageBits = 12;
  /// The kept value of cell `at` (NaN until computed), its page made on first touch.
  double& term(std::size_t at);
  /// Per grid cell: the logarithm of its term (or the term itself, for LF_alternateAverageMethod),
  /// NaN until computed. In pages made when a scan first reaches them: a view over a sparse map's
  /// wide bounding box is dense, and a double for each of its cells (as the stock grid keeps)
  /// would be eight times the view.
  std::vector<std::unique_ptr<double[]>> pages_;
  std::size_t cells_ = 0;
  bool logs_ = true;
};

}  // namespace rtog
