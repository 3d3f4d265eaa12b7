// Shared by the core and the MRPT tests: a map's leaves expanded into its cells.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "rtog/core/occupancy_map.hpp"

namespace rtog::test {

using CellValues = std::vector<std::pair<std::uint64_t, float>>;

/// Every known cell of `m` (packed key, log-odds), sorted by key.
inline CellValues cellsOf(const OccupancyMap& m) {
  CellValues out;
  m.forEachLeaf([&](const Box& b, float v) {
    for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
      for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
        for (std::int32_t x = b.min.x; x <= b.max.x; ++x) out.emplace_back(packKey(Key{x, y, z}), v);
  });
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

}  // namespace rtog::test
