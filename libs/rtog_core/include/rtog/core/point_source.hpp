// A scan's end points read piece by piece (OccupancyMap::insertPointSource): a scan given in its
// sensor's frame is moved into the map frame by the insertion threads, a few thousand points at
// a time, instead of whole into a buffer first (a depth frame: 3 MB, faulted in by one thread).
#pragma once

#include <cstddef>
#include <functional>

#include <Eigen/Core>

namespace rtog {

struct PointSource {
  /// The source's points are numbered 0 .. count - 1.
  std::size_t count = 0;
  /// Writes those of points [first, first + n) that are beams, in order, into `out` (room for
  /// n; map frame, metres) and returns how many it wrote. Called from several threads at once;
  /// the first points may be read twice (once to test whether the scan is planar), every other
  /// point once. So the beams a source drops are count minus the insertion's raysTotal().
  std::function<std::size_t(std::size_t first, std::size_t n, Eigen::Vector3f* out)> read;
};

}  // namespace rtog
