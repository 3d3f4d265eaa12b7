// Pose uncertainty blurred into one scan's update (OccupancyMap::insertBlurred): the scan traced
// from each pose of a weighted sample set by its sensor model's rules, each cell's probabilities
// mixed (mixture.hpp), the mixture one graded scan (UpdateSet::Kind::Graded).
#pragma once

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <cstdint>

#include "integrate/update_set.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/pose_blur.hpp"

namespace rtog {

/// The sum of a blur's n weights, weight(i) each; throws std::invalid_argument naming the first
/// that is not positive and finite, or if the sum is not finite.
template <class Weight>
double weightSum(std::size_t n, Weight&& weight) {
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weight(i);
    if (!(std::isfinite(w) && w > 0.0))
      throw std::invalid_argument("insertBlurred: weight " + std::to_string(i) + " is not positive and finite");
    total += w;
  }
  if (!std::isfinite(total)) throw std::invalid_argument("insertBlurred: the weights' sum is not finite");
  return total;
}

class PoseBlurIntegrator {
 public:
  explicit PoseBlurIntegrator(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// Throws std::invalid_argument for a weight that is not positive and finite,
  /// std::out_of_range for an origin without a key.
  UpdateSet trace(const WeightedScan* scans, std::size_t n, const InsertParams& ip);
  /// The scan traced once at the mean pose and moved to each pose (pose_resample.cpp). Throws
  /// as trace() does, and std::invalid_argument for a move that is not finite.
  /// Moving a trace costs a few walked cells per cell and pose (a lookup, the mixture's sum):
  /// worth it where beams cross each touched cell many times (a depth image at 5 cm: ~150; a
  /// LiDAR sweep or a 2D scan: ~1.1). InsertParams::blur_method = Auto moves where the beams
  /// cross this many times the cells of the scan's bounding box, or more.
  static constexpr double kMoveRatio = 8.0;
  UpdateSet resample(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                     const std::uint8_t* is_hit, const PoseMove* moves, std::size_t n, const InsertParams& ip);

 private:
  /// trace() of the scan moved by each move.
  UpdateSet traceMoved(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                       const std::uint8_t* is_hit, const PoseMove* moves, std::size_t n, const InsertParams& ip);

  IntegrationContext ctx_;
};

}  // namespace rtog
