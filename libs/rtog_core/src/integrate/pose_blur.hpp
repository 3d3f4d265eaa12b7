// Pose uncertainty blurred into one scan's update (OccupancyMap::insertBlurred): the scan traced
// from each pose of a weighted sample set by its sensor model's rules, each cell's probabilities
// mixed (mixture.hpp), the mixture one graded scan (UpdateSet::Kind::Graded).
#pragma once

#include <cstddef>

#include "integrate/update_set.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/pose_blur.hpp"

namespace rtog {

class PoseBlurIntegrator {
 public:
  explicit PoseBlurIntegrator(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// Throws std::invalid_argument for a weight that is not positive and finite,
  /// std::out_of_range for an origin without a key.
  UpdateSet trace(const WeightedScan* scans, std::size_t n, const InsertParams& ip);

 private:
  IntegrationContext ctx_;
};

}  // namespace rtog
