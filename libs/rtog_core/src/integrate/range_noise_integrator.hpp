// The range-noise sensor model (SensorModel::RangeNoise): each beam's cells take graded changes
// from the range likelihood, traced into per-thread graded scans (UpdateSet::Kind::Graded).
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "integrate/update_set.hpp"
#include "rtog/core/params.hpp"

namespace rtog {

class RangeNoiseIntegrator {
 public:
  explicit RangeNoiseIntegrator(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// Throws std::out_of_range for an origin without a key.
  UpdateSet trace(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                  const InsertParams& ip, const std::uint8_t* is_hit);

 private:
  IntegrationContext ctx_;
};

}  // namespace rtog
