// Fusion of another map by the independent opinion pool (OccupancyMap::fuse; the estimator seed,
// section 3): the other map's evidence, placed by a pose and resampled into this lattice
// (fusion_resample.hpp), enters as one graded update whose change in a cell is the evidence there
// (l2 - l0), each cell once, through the graded path range-noise scans take
// (UpdateSet::Kind::Graded). Under uncertain poses each cell takes the change of the mixture of
// the placements' probabilities (mixture.hpp), the rule of pose blur.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "integrate/update_set.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

class FusionIntegrator {
 public:
  explicit FusionIntegrator(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// `other` placed by a rigid pose (checked by the caller).
  UpdateSet trace(const OccupancyMap& other, const Eigen::Isometry3d& pose, int threads);
  /// `other` placed by weighted rigid poses, weights summing to 1 (checked by the caller).
  UpdateSet trace(const OccupancyMap& other, const std::vector<OccupancyMap::WeightedPose>& poses, int threads);

 private:
  IntegrationContext ctx_;
};

}  // namespace rtog
