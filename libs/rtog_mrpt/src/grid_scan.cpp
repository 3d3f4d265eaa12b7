#include "grid_scan.hpp"

#include <algorithm>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "mrpt_grid.hpp"

namespace rtog::mrpt_grid {

bool insertScan(OccupancyMap& map, TGridFrame2D& frame, const mrpt::obs::CObservation2DRangeScan& scan,
                const mrpt::poses::CPose3D& robotPose, const CRTreeOccupancyGridMap::TInsertionOptions& io,
                CRTreeOccupancyGridMap::GridScanUpdate* update, InsertStats& stats, std::size_t& invalid) {
  // Per call, not kept: a scan's buffers are small beside its work, and kept per thread they
  // would be heap the map holds after its last scan.
  ScanPlan plan;
  if (!planScan(scan, robotPose, io, frame, plan)) return false;
  // Everything on copies until the map took the steps: a throw leaves map and geometry as they were.
  TGridFrame2D grown = frame;
  resize(grown, plan.grow[0], plan.grow[1], plan.grow[2], plan.grow[3]);
  if (!grown.has_layer) {
    const double z = (robotPose + scan.sensorPose).z();
    Key k;
    if (!map.lattice().tryKey(Eigen::Vector3d(0, 0, z), k))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: a 2D scan's height has no key");
    grown.has_layer = true;
    grown.layer = k.z;
  }
  stats = InsertStats{};
  std::vector<OccupancyMap::StepRun> own_runs;
  std::vector<OccupancyMap::StepRun>& runs = update ? update->runs : own_runs;
  traceScan(scan, plan, io, grown, runs, stats);
  if (update) std::copy(std::begin(plan.grow), std::end(plan.grow), update->grow);
  const StepRule rule = stepRule(stepsOf(io));
  stats += map.applyStepRuns(grown.layer, runs.data(), runs.size(), rule, update ? &update->after : nullptr);
  frame = grown;
  invalid = invalidNotFree(scan, io);
  return true;
}

}  // namespace rtog::mrpt_grid
