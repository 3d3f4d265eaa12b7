// What an insertion did and what a map holds.
#pragma once

#include <cstddef>
#include <cstdint>

#include "rtog/core/key.hpp"

namespace rtog {

/// What one insertion did; every input beam is counted in exactly one of the first seven.
struct InsertStats {
  std::size_t rays_hit = 0;              ///< beams that marked an occupied end cell
  std::size_t rays_truncated = 0;        ///< beams cut at max_range or flagged as no-return
  std::size_t skipped_non_finite = 0;    ///< NaN/Inf end points
  std::size_t skipped_zero_length = 0;   ///< end point at the origin (no direction)
  std::size_t skipped_out_of_range = 0;  ///< end point outside the key range
  std::size_t skipped_too_long = 0;      ///< longer than InsertParams::max_ray_cells cells
  std::size_t skipped_over_budget = 0;   ///< of scans over InsertParams::max_scan_cells, skipped whole
  std::size_t cells_occupied = 0;        ///< distinct cells updated as occupied
  std::size_t cells_free = 0;            ///< distinct cells updated as free
  std::size_t cells_unchanged = 0;       ///< updates absorbed by clamping
  // The leaf count changes by leaves_created - leaves_merged. A brick rebuilt in one pass (many
  // updates, or the planar cache covered again) counts its new leaves as created and its old ones
  // as merged away. Scans held in the planar cache report their leaves in flush().
  std::size_t leaves_created = 0;
  std::size_t leaves_merged = 0;         ///< merges performed (each removes one leaf)
  std::size_t leaves_split = 0;          ///< merged cuboids split by disagreeing evidence

  std::size_t raysTotal() const {
    return rays_hit + rays_truncated + skipped_non_finite + skipped_zero_length + skipped_out_of_range +
           skipped_too_long + skipped_over_budget;
  }
  InsertStats& operator+=(const InsertStats& o);
  bool operator==(const InsertStats& o) const;
};

/// Whole-map figures (what `rtog info` prints).
struct MapStatistics {
  std::size_t leaves = 0, occupied_leaves = 0, free_leaves = 0;
  std::int64_t cells = 0, occupied_cells = 0, free_cells = 0;
  std::size_t bricks = 0;
  int tree_height = 0;
  std::size_t tree_nodes = 0;
  std::size_t memory_bytes = 0;
  Box bounds = Box::empty();
};

/// Leaves of a cover that keeps only each cell's class (see OccupancyMap::classCover).
struct ClassCover {
  std::size_t occupied = 0, free = 0;
  std::size_t leaves() const { return occupied + free; }
};

/// Counts of cells in a box by state.
struct BoxSummary {
  std::int64_t occupied = 0, free = 0, unknown = 0;
};

}  // namespace rtog
