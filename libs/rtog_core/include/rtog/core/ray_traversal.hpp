// Exact voxel traversal of a segment (Amanatides & Woo 1987) on the integer lattice.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <limits>

#include <Eigen/Core>

#include "rtog/core/key.hpp"

namespace rtog {

/// Walks the cells the segment from `from` to `to` (continuous lattice coordinates, whose
/// cells are `from_key` and `to_key`) passes through, starting with `from_key` and stopping
/// before `to_key`: at each cell calls cursor.visit(), then cursor.move(axis, dir) (axis a constant at each call).
/// Every step moves one axis one cell towards `to_key` and an axis that reached the end
/// coordinate never steps again, so the walk visits exactly |dx|+|dy|+|dz| cells and always
/// ends at `to_key`, whatever the rounding. Ties go to x, then y. Returns the cell count.
template <class Cursor>
std::int64_t walkRay(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key,
                     Cursor& cursor) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d d = to - from;
  int step[3];
  double t_max[3], t_delta[3];
  std::int64_t n = 0;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t diff = std::int64_t{to_key[a]} - from_key[a];
    n += diff < 0 ? -diff : diff;
    step[a] = diff > 0 ? 1 : (diff < 0 ? -1 : 0);
    if (step[a] == 0) {
      t_max[a] = t_delta[a] = inf;
    } else {
      // d[a] has the sign of diff: the keys differ only if the coordinates do.
      const double boundary = step[a] > 0 ? double(from_key[a]) + 1.0 : double(from_key[a]);
      t_delta[a] = double(step[a]) / d[a];
      t_max[a] = (boundary - from[a]) / d[a];
    }
  }
  // Scalars, not arrays indexed by the chosen axis: keeps the loop in registers (~2 ns/step).
  std::int32_t x = from_key.x, y = from_key.y, z = from_key.z;
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  if (step[2] == 0) {
    // The same walk for a segment within one z-layer (a 2D scan): one comparison per step
    // instead of two, 10 % less time on the SENA rays.
    for (std::int64_t i = 0; i < n; ++i) {
      cursor.visit();
      if (tx <= ty) {
        x += step[0];
        tx = x == to_key.x ? inf : tx + t_delta[0];
        cursor.move(0, step[0]);
      } else {
        y += step[1];
        ty = y == to_key.y ? inf : ty + t_delta[1];
        cursor.move(1, step[1]);
      }
    }
    return n;
  }
  for (std::int64_t i = 0; i < n; ++i) {
    cursor.visit();
    if (tx <= ty && tx <= tz) {
      x += step[0];
      tx = x == to_key.x ? inf : tx + t_delta[0];
      cursor.move(0, step[0]);
    } else if (ty <= tz) {
      y += step[1];
      ty = y == to_key.y ? inf : ty + t_delta[1];
      cursor.move(1, step[1]);
    } else {
      z += step[2];
      tz = z == to_key.z ? inf : tz + t_delta[2];
      cursor.move(2, step[2]);
    }
  }
  return n;
}

/// walkRay with a visitor: calls visit(key) for every cell of the walk.
template <class Visit>
std::int64_t traverseRay(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                         const Key& to_key, Visit&& visit) {
  struct KeyCursor {
    Key k;
    Visit& fn;
    void visit() { fn(k); }
    void move(int axis, int s) { k[axis] += s; }
  } cursor{from_key, visit};
  return walkRay(from, to, from_key, to_key, cursor);
}

}  // namespace rtog
