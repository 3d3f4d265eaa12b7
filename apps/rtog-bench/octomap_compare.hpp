// Cell-by-cell comparison of an rtog map with an OctoMap tree on the same lattice.
#pragma once

#include <cstdint>

#include <octomap/OcTree.h>

#include "rtog/core/occupancy_map.hpp"

namespace rtog::bench {

struct Agreement {
  std::int64_t both = 0;          ///< cells known to both maps
  std::int64_t agree = 0;         ///< of those, same occupied/free class
  std::int64_t only_rtog = 0, only_octomap = 0;
  double ratio() const { return both ? double(agree) / double(both) : 0.0; }
};

/// OctoMap keys are lattice keys offset by 2^15 at the finest depth (same cell boundaries as
/// rtog's lattice); a pruned leaf stands for a cube of cells.
Agreement compareWithOctomap(const OccupancyMap& map, const octomap::OcTree& tree);

}  // namespace rtog::bench
