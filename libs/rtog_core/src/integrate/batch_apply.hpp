// Applying a scan's update batches to the map: brick by brick, in parallel, then the upper tree.
#pragma once

#include <vector>

#include "integrate/brick_update.hpp"
#include "integrate/graded_scan.hpp"
#include "integrate/update_batch.hpp"
#include "rtog/core/stats.hpp"
#include "storage/map_store.hpp"

namespace rtog {

/// Applies the union of finalized batches (occupied winning over free across batches too) to
/// the map, brick by brick on up to `threads` threads with contexts[t] each (resized as needed),
/// and brings the upper tree up to date. The map does not depend on the thread count.
void applyBatches(MapStore& store, const std::vector<const UpdateBatch*>& batches, InsertStats& stats, int threads,
                  std::vector<ApplyContext>& contexts);

/// Applies the union of finalized graded scans (per cell the largest change; miss masks or-ed)
/// to the map, brick by brick on up to `threads` threads, and brings the upper tree up to date.
/// The map does not depend on the thread count, nor on how the beams were split among the scans.
void applyGraded(MapStore& store, const std::vector<const GradedScan*>& scans, InsertStats& stats, int threads,
                 std::vector<ApplyContext>& contexts);

}  // namespace rtog
