// Exact voxel traversal of a segment (Amanatides & Woo 1987) on the integer lattice.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <limits>

#include <Eigen/Core>

#include "rtog/core/key.hpp"

namespace rtog {

/// Calls visit(key) for every cell the segment from `from` to `to` (continuous lattice
/// coordinates, whose cells are `from_key` and `to_key`) passes through, starting with
/// `from_key` and stopping before `to_key`. Every step moves one axis one cell towards
/// `to_key`, so the walk visits exactly |dx|+|dy|+|dz| cells and always ends at `to_key`,
/// whatever the rounding. Returns the number of cells visited.
template <class Visit>
std::int64_t traverseRay(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                         const Key& to_key, Visit&& visit) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d d = to - from;
  Key cur = from_key;
  int step[3];
  double t_max[3], t_delta[3];
  std::int64_t remaining = 0;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t diff = std::int64_t{to_key[a]} - from_key[a];
    remaining += diff < 0 ? -diff : diff;
    step[a] = diff > 0 ? 1 : (diff < 0 ? -1 : 0);
    if (step[a] == 0) {
      t_max[a] = t_delta[a] = inf;
    } else {
      // d[a] has the sign of diff: the keys differ only if the coordinates do.
      const double boundary = step[a] > 0 ? double(cur[a]) + 1.0 : double(cur[a]);
      t_delta[a] = double(step[a]) / d[a];
      t_max[a] = (boundary - from[a]) / d[a];
    }
  }
  const std::int64_t n = remaining;
  while (remaining-- > 0) {
    visit(cur);
    const int a = t_max[0] <= t_max[1] ? (t_max[0] <= t_max[2] ? 0 : 2) : (t_max[1] <= t_max[2] ? 1 : 2);
    cur[a] += step[a];
    t_max[a] = cur[a] == to_key[a] ? inf : t_max[a] + t_delta[a];
  }
  return n;
}

}  // namespace rtog
