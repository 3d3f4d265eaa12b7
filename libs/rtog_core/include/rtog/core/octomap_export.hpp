// Export to OctoMap's binary tree format (.bt), readable by octovis and
// octomap::OcTree::readBinary, without linking OctoMap.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>

#include "rtog/core/occupancy_map.hpp"

namespace rtog {

/// OctoMap's tree: depth 16, key = lattice key + 2^15 on each axis.
constexpr int kOctoMapDepth = 16;
constexpr std::int32_t kOctoMapKeyOffset = 1 << (kOctoMapDepth - 1);

/// True when every cell of `b` has an OctoMap key (lattice keys in [-2^15, 2^15 - 1]).
constexpr bool inOctoMapKeyRange(const Box& b) {
  return b.min.x >= -kOctoMapKeyOffset && b.min.y >= -kOctoMapKeyOffset && b.min.z >= -kOctoMapKeyOffset &&
         b.max.x < kOctoMapKeyOffset && b.max.y < kOctoMapKeyOffset && b.max.z < kOctoMapKeyOffset;
}

/// What writeOctoMapBinary wrote.
struct OctoMapExportStats {
  std::size_t nodes = 0;            ///< the header's `size`: root, inner nodes and leaves
  std::size_t inner_nodes = 0;      ///< nodes with children (the root included)
  std::size_t occupied_leaves = 0;  ///< octree leaves (a pruned leaf counts once)
  std::size_t free_leaves = 0;
};

/// Writes `map` as an OctoMap binary tree: the text header (`# Octomap OcTree binary file`,
/// `id OcTree`, `size`, `res`, `data`) and then, depth first from the root, two bytes per inner
/// node holding the 2-bit states of its 8 children. Only the maximum-likelihood class of each
/// cell is kept (as in OctoMap's own `writeBinary`): occupied and free cells become leaves
/// at OctoMap's clamping bounds, unknown cells have no node, and 8 children of one class are
/// pruned into their parent. The map's lattice is OctoMap's, so cell keys carry over.
/// Throws std::out_of_range, naming the first offending leaf, if a cell lies outside OctoMap's
/// 16-bit key range (nothing is written then), and std::runtime_error if the stream fails.
OctoMapExportStats writeOctoMapBinary(const OccupancyMap& map, std::ostream& os);

}  // namespace rtog
