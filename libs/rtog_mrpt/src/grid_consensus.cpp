// rtog::boundedConsensusLikelihood: MRPT's lmConsensus, bounded (see grid_consensus.hpp).
#include "grid_consensus.hpp"

#include <algorithm>
#include <cmath>

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/math/TPoint2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

namespace rtog {

namespace {
/// The cell MRPT's x2idx/y2idx pick, or unknown (0.5, what getCell gives off the grid) when that
/// index is not in the grid. MRPT truncates toward zero: an end point less than one cell before
/// the grid's first cell reads that cell, as in MRPT (no crash there). Written so that a NaN
/// reads as unknown too.
float cellOrUnknown(const mrpt::maps::COccupancyGridMap2D& g, double x, double y) {
  const double fx = (x - g.getXMin()) / g.getResolution(), fy = (y - g.getYMin()) / g.getResolution();
  if (!(fx > -1.0 && fx < double(g.getSizeX()) && fy > -1.0 && fy < double(g.getSizeY()))) return 0.5f;
  return g.getCell(g.x2idx(x), g.y2idx(y));
}
}  // namespace

std::optional<double> boundedConsensusLikelihood(const mrpt::maps::COccupancyGridMap2D& g,
                                                 const mrpt::obs::CObservation& obs, const mrpt::poses::CPose2D& pose) {
  if (!IS_CLASS(obs, mrpt::obs::CObservation2DRangeScan)) return std::nullopt;
  const auto& scan = static_cast<const mrpt::obs::CObservation2DRangeScan&>(obs);
  if (!scan.isPlanarScan(g.insertionOptions.horizontalTolerance)) return std::nullopt;
  const auto* points = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>();
  // A step of 0 (refused by the options' checks) would loop for ever in MRPT's: one at a time.
  const std::size_t step = std::max(1, g.likelihoodOptions.consensus_takeEachRange);
  double lik = 0;
  std::size_t denom = 0;
  const std::size_t n = points->size();
  for (std::size_t i = 0; i < n; i += step) {
    mrpt::math::TPoint2D local, global;
    points->getPoint(i, local);
    pose.composePoint(local, global);
    lik += 1 - cellOrUnknown(g, global.x, global.y);  // float arithmetic then added, as MRPT's
    ++denom;
  }
  if (denom) lik /= denom;
  lik = std::pow(lik, static_cast<double>(g.likelihoodOptions.consensus_pow));
  return std::log(lik);
}

}  // namespace rtog
