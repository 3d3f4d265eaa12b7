// rtog::CRTreeOccupancyGridMap: 2D range scans in the mrpt_grid preset, stepped into the
// R-tree map as COccupancyGridMap2D steps its cells (see mrpt_grid.hpp).
#include <stdexcept>

#include "mrpt_grid.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

void CRTreeOccupancyGridMap::setGridFrame(float x_min, float x_max, float y_min, float y_max) {
  if (!isEmpty()) throw std::logic_error("rtog::CRTreeOccupancyGridMap::setGridFrame: the map holds cells");
  TGridFrame2D f;
  mrpt_grid::setSize(f, x_min, x_max, y_min, y_max, static_cast<float>(map_.resolution()));
  frame_ = f;
}

bool CRTreeOccupancyGridMap::insertGridScan(const mrpt::obs::CObservation2DRangeScan& scan,
                                            const mrpt::poses::CPose3D& robotPose, GridScanUpdate* update) {
  syncParams();
  const TInsertionOptions& io = insertionOptions;
  // Per call, not kept: a scan's buffers are small beside its work, and kept per thread they
  // would be heap the map holds after its last scan.
  mrpt_grid::ScanPlan plan;
  if (!mrpt_grid::planScan(scan, robotPose, io, frame_, plan)) return false;
  // Everything on copies until the map took the steps: a throw leaves map and geometry as they were.
  TGridFrame2D grown = frame_;
  mrpt_grid::resize(grown, plan.grow[0], plan.grow[1], plan.grow[2], plan.grow[3]);
  if (!grown.has_layer) {
    const double z = (robotPose + scan.sensorPose).z();
    Key k;
    if (!map_.lattice().tryKey(Eigen::Vector3d(0, 0, z), k))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: a 2D scan's height has no key");
    grown.has_layer = true;
    grown.layer = k.z;
  }
  InsertStats stats;
  std::vector<OccupancyMap::StepRun> own_runs;
  std::vector<OccupancyMap::StepRun>& runs = update ? update->runs : own_runs;
  mrpt_grid::traceScan(scan, plan, io, grown, runs, stats);
  if (update) std::copy(std::begin(plan.grow), std::end(plan.grow), update->grow);
  const StepRule rule = mrpt_grid::stepRule(mrpt_grid::stepsOf(io));
  stats += map_.applyStepRuns(grown.layer, runs.data(), runs.size(), rule, update ? &update->after : nullptr);
  frame_ = grown;
  std::size_t invalid = 0;
  if (!io.considerInvalidRangesAsFreeSpace)
    for (std::size_t i = 0; i < scan.getScanSize(); i += io.decimation) invalid += scan.getScanRangeValidity(i) ? 0 : 1;
  invalidRangesSkipped += invalid;
  lastInsertStats = stats;
  totalInsertStats += stats;
  notifyMapChanged();
  return true;
}

}  // namespace rtog
