#include "grid_graded.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>


namespace rtog::mrpt_grid {
namespace {

std::uint64_t packKey3(const Key& k) {
  return std::uint64_t(std::uint32_t(k.x - kKeyMin)) | std::uint64_t(std::uint32_t(k.y - kKeyMin)) << 21 |
         std::uint64_t(std::uint32_t(k.z - kKeyMin)) << 42;
}

/// One pose's beams as steps, beam by beam in the grid's order: each run's cells, then its end
/// cell; a hit beam with range noise by gradeBeam().
void poseSteps(const std::vector<OccupancyMap::StepRun>& runs, const std::vector<float>& ranges,
               const RangeNoiseRule* noise, const Steps& whole, const TGridFrame2D& f, std::vector<CellStep>& out) {
  constexpr int F = OccupancyMap::kRunFracBits;
  const std::int32_t ox = keyOffsetX(f), oy = keyOffsetY(f), z = f.layer;
  for (std::size_t j = 0; j < runs.size(); ++j) {
    const OccupancyMap::StepRun& r = runs[j];
    const double R = ranges[j];
    const double sigma = noise && r.end && r.count > 0 ? noise->sigma(R) : 0.0;
    if (!(sigma > 0.0)) {
      OccupancyMap::forEachRunCell(r, [&](std::int32_t x, std::int32_t y, StepKind k) {
        const int size = k == StepKind::Occupied ? whole.occupied : k == StepKind::Free ? whole.free : whole.noecho;
        out.push_back(CellStep{Key{x, y, z}, k, static_cast<std::uint8_t>(size)});
      });
      continue;
    }
    const Key end{r.end_x, r.end_y, z};
    gradeBeam(*noise, R, sigma, r.count, &end, whole, [&](std::uint32_t i, Key& k) {
      k = Key{static_cast<std::int32_t>((std::int64_t{r.x} * (1 << F) + std::int64_t{i} * r.dx) >> F),
              static_cast<std::int32_t>((std::int64_t{r.y} * (1 << F) + std::int64_t{i} * r.dy) >> F), z};
      return static_cast<std::uint32_t>(k.x - ox) < f.size_x && static_cast<std::uint32_t>(k.y - oy) < f.size_y;
    }, out);
  }
}

}  // namespace

void PoseMixture::add(double weight, const std::vector<CellStep>& steps) {
  if (!several_) {  // the grid's order, on the map's cells
    for (const CellStep& c : steps) {
      std::int8_t& v = at(c.key);
      v = stepCell(v, c.kind, c.size, whole_);
    }
    return;
  }
  own_.clear();
  now_.clear();
  for (const CellStep& c : steps) {
    const auto next = static_cast<std::uint32_t>(now_.size());
    const std::uint32_t i = own_.findOrInsert(packKey3(c.key), next);
    if (i == next) now_.emplace_back(c.key, peek(c.key));
    now_[i].second = stepCell(now_[i].second, c.kind, c.size, whole_);
  }
  for (const auto& [key, v] : now_) {
    const auto next = static_cast<std::uint32_t>(sums_.size());
    const std::uint32_t i = index_.findOrInsert(packKey3(key), next);
    if (i == next) sums_.emplace_back(key, 0.0);
    sums_[i].second += mix_.term(weight, valueOfCell(v) - valueOfCell(peek(key)));
  }
}

InsertStats PoseMixture::writeBack(OccupancyMap& map) {
  for (const auto& [key, sum] : sums_) {
    const int before = peek(key);
    const int after = std::clamp(before - gradedUnits(mix_.change(sum)), -127, 127);
    if (after != before) at(key) = static_cast<std::int8_t>(after);
  }
  return cells_.writeBack(map);
}

bool insertGradedScan(OccupancyMap& map, TGridFrame2D& frame, const mrpt::obs::CObservation2DRangeScan& scan,
                      const std::vector<pose_sigma::SigmaPose>& poses, const CRTreeOccupancyGridMap::TInsertionOptions& io,
                      InsertStats& stats, std::size_t& invalid) {
  std::optional<RangeNoiseRule> noise;
  if (sensorModelFromString(io.sensorModel) == SensorModel::RangeNoise) noise.emplace(map.logOddsModel(), io.toInsertParams());
  const RangeNoiseRule* rule = noise ? &*noise : nullptr;
  // Every pose planned on the grid as it grows (a throw leaves map and geometry as they were),
  // then traced on the grown grid.
  TGridFrame2D grown = frame;
  std::vector<std::optional<ScanPlan>> plans(poses.size());
  double mean_z = 0.0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    ScanPlan plan;
    if (!planScan(scan, poses[i].pose, io, grown, plan)) continue;  // this pose says nothing of any cell
    resize(grown, plan.grow[0], plan.grow[1], plan.grow[2], plan.grow[3]);
    plans[i] = std::move(plan);
    mean_z += poses[i].weight * (poses[i].pose + scan.sensorPose).z();
  }
  if (std::none_of(plans.begin(), plans.end(), [](const auto& p) { return p.has_value(); })) return false;
  if (!grown.has_layer) {
    Key k;
    const double z = poses.size() == 1 ? (poses[0].pose + scan.sensorPose).z() : mean_z;
    if (!map.lattice().tryKey(Eigen::Vector3d(0, 0, z), k))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: a 2D scan's height has no key");
    grown.has_layer = true;
    grown.layer = k.z;
  }
  const Steps whole = stepsOf(io);
  stats = InsertStats{};
  bool counted = false;
  std::vector<OccupancyMap::StepRun> runs;
  std::vector<float> ranges;
  std::vector<CellStep> steps;
  PoseMixture mixture(map, whole, poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!plans[i]) continue;
    InsertStats pose_stats;
    traceScan(scan, *plans[i], io, grown, runs, pose_stats, &ranges);
    if (!counted) stats = pose_stats, counted = true;
    steps.clear();
    poseSteps(runs, ranges, rule, whole, grown, steps);
    mixture.add(poses[i].weight, steps);
  }
  const InsertStats written = mixture.writeBack(map);
  stats.cells_free = written.cells_free, stats.cells_occupied = written.cells_occupied;
  stats.leaves_created = written.leaves_created, stats.leaves_merged = written.leaves_merged;
  frame = grown;
  invalid = 0;
  if (!io.considerInvalidRangesAsFreeSpace)
    for (std::size_t i = 0; i < scan.getScanSize(); i += io.decimation) invalid += scan.getScanRangeValidity(i) ? 0 : 1;
  return true;
}

}  // namespace rtog::mrpt_grid
