// Private to librtog_mrpt: the likelihood field (lmLikelihoodField_Thrun) of a planar scan on
// the 2D view, each cell's term computed once and kept with its logarithm. The value is
// COccupancyGridMap2D::computeObservationLikelihood's for the same grid, scan and pose, bit for
// bit (tested); what it saves is the sine and cosine of the pose and the logarithm of the term
// that the stock grid computes again for every point.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

namespace rtog {

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
