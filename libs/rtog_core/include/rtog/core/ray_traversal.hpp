// Exact voxel traversal of a segment (Amanatides & Woo 1987) on the integer lattice.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include <Eigen/Core>

#include "rtog/core/key.hpp"

namespace rtog {

/// A segment within one z-layer in exact integer form. The end points are rounded to 2^-shift
/// of a cell, kept inside their cells, and mirrored so that both axes step up. Crossing times
/// of cell boundaries then compare as exact integer products: no rounding decides an order or
/// a tie, so a walk cell by cell and a walk by runs of cells (PlanarBatch) give the same cells.
struct PlanarSegment {
  std::int64_t nx = 0, ny = 0;  ///< cells to step along x and y
  int sx = 1, sy = 1;           ///< their directions on the lattice
  int shift = 0;                ///< fixed-point fraction bits
  std::int64_t x0 = 0, y0 = 0;  ///< start, fixed point, mirrored, relative to the start cell
  std::int64_t dx = 0, dy = 0;  ///< extent, fixed point, mirrored; > 0 where nx, ny > 0
};

namespace detail {
inline int bitWidth(std::uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); }
// One axis of planarSegment: start and end in fixed point relative to the start cell, clamped
// into their cells and mirrored for a step down.
inline void fixedAxis(double from, double to, std::int32_t from_cell, std::int32_t to_cell, int shift,
                      std::int64_t& n, int& s, std::int64_t& start, std::int64_t& extent) {
  const std::int64_t one = std::int64_t{1} << shift, k = std::int64_t{to_cell} - from_cell;
  const double scale = static_cast<double>(one);
  const auto a = std::min(std::max(static_cast<std::int64_t>(std::floor((from - from_cell) * scale)), std::int64_t{0}),
                          one - 1);
  const auto b = std::min(std::max(static_cast<std::int64_t>(std::floor((to - from_cell) * scale)), k * one),
                          k * one + one - 1);
  s = k < 0 ? -1 : 1;
  n = k < 0 ? -k : k;
  start = k < 0 ? one - 1 - a : a;
  extent = (k < 0 ? one - 1 - b : b) - start;
}
}  // namespace detail

/// The exact form of the segment from `from` to `to` (continuous lattice coordinates, x and y;
/// cells `from_key` and `to_key`). The fraction bits keep every product of the walk below 2^62.
inline PlanarSegment planarSegment(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                                   const Key& to_key) {
  PlanarSegment seg;
  const auto nx = static_cast<std::uint64_t>(std::abs(std::int64_t{to_key.x} - from_key.x));
  const auto ny = static_cast<std::uint64_t>(std::abs(std::int64_t{to_key.y} - from_key.y));
  seg.shift = std::min(20, (62 - detail::bitWidth(nx + 2) - detail::bitWidth(ny + 2)) / 2);
  detail::fixedAxis(from.x(), to.x(), from_key.x, to_key.x, seg.shift, seg.nx, seg.sx, seg.x0, seg.dx);
  detail::fixedAxis(from.y(), to.y(), from_key.y, to_key.y, seg.shift, seg.ny, seg.sy, seg.y0, seg.dy);
  return seg;
}

/// The cell-by-cell walk of a planar segment; as walkRay. Boundary m of x is crossed at time
/// (m * 2^shift - x0) / dx, so x first (ties too) while (m_x 2^shift - x0) dy <= (m_y 2^shift - y0) dx.
template <class Cursor>
std::int64_t walkPlanar(const PlanarSegment& seg, Cursor& cursor) {
  const std::int64_t n = seg.nx + seg.ny;
  if (n == 0) return 0;
  if (seg.nx == 0 || seg.ny == 0) {
    const int axis = seg.nx == 0 ? 1 : 0, dir = seg.nx == 0 ? seg.sy : seg.sx;
    for (std::int64_t i = 1; i < n; ++i) {
      cursor.visit();
      cursor.move(axis, dir);
    }
    cursor.visit();
    return n;
  }
  const std::int64_t one = std::int64_t{1} << seg.shift;
  const std::int64_t step_x = one * seg.dy, step_y = one * seg.dx;
  std::int64_t ex = (one - seg.x0) * seg.dy, ey = (one - seg.y0) * seg.dx;
  for (std::int64_t i = 1; i < n; ++i) {
    cursor.visit();
    if (ex <= ey) {
      ex += step_x;
      cursor.move(0, seg.sx);
    } else {
      ey += step_y;
      cursor.move(1, seg.sy);
    }
  }
  cursor.visit();
  return n;
}

namespace detail {
/// walkRay's set-up of a segment that leaves its z-layer: per axis the step (-1, 0 or 1), the
/// time of the first boundary crossing and the time between crossings (infinite for an axis
/// that does not step). Returns the number of steps. Shared with the batch's AVX2 lanes, which
/// must take every decision from the same doubles.
inline std::int64_t setUpWalk(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                              const Key& to_key, int step[3], double t_max[3], double t_delta[3]) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d d = to - from;
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
  return n;
}
}  // namespace detail

/// Walks the cells the segment from `from` to `to` (continuous lattice coordinates, whose
/// cells are `from_key` and `to_key`) passes through, starting with `from_key` and stopping
/// before `to_key`: at each cell calls cursor.visit(), then, but for the last,
/// cursor.move(axis, dir) (axis a constant at each call).
/// Every step moves one axis one cell towards `to_key` and an axis that reached the end
/// coordinate never steps again, so the walk visits exactly |dx|+|dy|+|dz| cells and always
/// ends at `to_key`, whatever the rounding. Ties go to x, then y. A segment within one z-layer
/// is walked in its exact integer form (planarSegment). Returns the cell count.
template <class Cursor>
std::int64_t walkRay(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key,
                     Cursor& cursor) {
  // Before the floating-point set-up below, which a planar segment does not use.
  if (from_key.z == to_key.z) return walkPlanar(planarSegment(from, to, from_key, to_key), cursor);
  constexpr double inf = std::numeric_limits<double>::infinity();
  int step[3];
  double t_max[3], t_delta[3];
  const std::int64_t n = detail::setUpWalk(from, to, from_key, to_key, step, t_max, t_delta);
  if (n == 0) return 0;
  // Scalars, not arrays indexed by the chosen axis: keeps the loop in registers (~2 ns/step).
  std::int32_t x = from_key.x, y = from_key.y, z = from_key.z;
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  for (std::int64_t i = 1; i < n; ++i) {
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
  cursor.visit();
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
