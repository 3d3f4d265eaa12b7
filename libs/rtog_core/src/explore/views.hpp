// What the view scoring shares (info_gain.cpp, views.cpp).
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "explore/cell_reader.hpp"
#include "rtog/core/explore.hpp"

namespace rtog::explore_detail {

/// A ray whose reach falls under this stops (rtog/core/explore.hpp).
constexpr double kMinReach = 1e-3;

/// Entropy of a probability, in bits.
double entropyBits(double p);
/// The expected entropy reduction of a cell of log-odds `log_odds` that a ray reaches.
double cellGain(const LogOddsModel& model, float log_odds);
/// informationGain with the cells read through `cells` (kept between views).
ViewGain gainOf(CellReader& cells, const OccupancyMap& map, const Eigen::Isometry3d& pose,
                const std::vector<Eigen::Vector3d>& rays, double max_range);

}  // namespace rtog::explore_detail
