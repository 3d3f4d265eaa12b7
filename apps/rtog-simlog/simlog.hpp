// rtog-simlog: a long, reproducible 2D laser log made from a map: a closed loop planned through
// the map's free space, driven by a simulated robot with noisy odometry, written as an MRPT
// action/sensory-frame rawlog (and the ground-truth path beside it). Used to benchmark the real
// MRPT SLAM apps on more than the few hundred scans of the logs Debian ships (issue #39).
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include <mrpt/math/TPoint2D.h>

namespace mrpt::maps {
class COccupancyGridMap2D;
}

namespace rtog::simlog {

/// How the loop is planned (loop.cpp).
struct LoopOptions {
  double clearance = 1.0;  ///< The robot keeps this far from anything not known free [m]
  double smoothing = 2.0;  ///< Half-width of the moving average rounding the loop's corners [m]
};

/// A closed loop through the free space of `world` (cells 1: free, 0: solid), in metres, the
/// last point joined back to the first. Deterministic: the largest region the robot fits in,
/// around the largest obstacle that region encloses, by the cheapest path that keeps away from
/// walls. Throws std::runtime_error if the map has no such loop. Says what it chose on `log`.
std::vector<mrpt::math::TPoint2D> planLoop(const mrpt::maps::COccupancyGridMap2D& world, const LoopOptions& opts,
                                           std::ostream& log);

/// The run: every option of the command line.
struct Options {
  std::string gridmap;      ///< input .gridmap / .gridmap.gz (a serialized COccupancyGridMap2D)
  std::string rawlog;       ///< output rawlog (action/sensory-frame)
  std::string gt;           ///< ground-truth path, "t x y phi" per line (empty: none)
  std::string png;          ///< the map with the loop drawn (empty: none)
  std::size_t scans = 3000;  ///< action/sensory-frame pairs; the loop is driven once, end at start
  std::uint32_t seed = 1;   ///< odometry and range noise
  double odometry_noise = 1.0;  ///< scales every odometry error term (0: exact odometry)
  bool reverse = false;         ///< drive the loop the other way round
  LoopOptions loop;
};

/// Reads the map, plans, drives, simulates and writes every output (all or none). Throws on
/// bad input with a one-line message.
void run(const Options& opts, std::ostream& log);

/// The command line; returns the exit code (0, 1 for a failed run, 2 for a usage error).
int main(int argc, char** argv, std::ostream& out, std::ostream& err);

}  // namespace rtog::simlog
