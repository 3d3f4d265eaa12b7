// The appliers: an update set's buffers applied to the map brick by brick, in parallel, then the
// upper tree. Called only by MapEngine::apply (the layout check holds it so).
#pragma once

#include <vector>

#include "integrate/brick_update.hpp"
#include "integrate/graded_scan.hpp"
#include "integrate/update_batch.hpp"
#include "rtog/core/stats.hpp"
#include "storage/map_store.hpp"

namespace rtog {

struct AssignedPiece;

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

/// Sets the pieces' cells to their values (CellAssignment): a map without leaves takes them as
/// its leaves, else each touched brick is covered anew; then the upper tree.
void applyAssigned(MapStore& store, const std::vector<AssignedPiece>& pieces, InsertStats& stats,
                   std::vector<ApplyContext>& contexts);

/// The upper tree brought up to date with the bricks contexts[0, n) reshaped; their counts added.
void refreshFromContexts(LeafIndex& index, std::vector<ApplyContext>& contexts, std::size_t n, InsertStats& stats);

}  // namespace rtog
