// The per-brick update: one brick's marks of a scan applied to its leaves, with splits of
// merged cuboids that disagree and merges of equal neighbours (seed §2.5).
#pragma once

#include <cstdint>
#include <vector>

#include "integrate/update_batch.hpp"
#include "rtog/core/stats.hpp"
#include "storage/map_store.hpp"

namespace rtog {

/// A cell of a graded update (a scan whose cells each have their own change): its brick-local
/// index and log-odds change l_meas - l0.
struct GradedCell {
  std::uint16_t local;
  float delta;
};

/// Per-thread state of applying bricks.
struct alignas(64) ApplyContext {
  std::vector<std::int32_t> local;  // brick-local cell -> leaf index, -1 when none
  std::vector<std::uint32_t> candidates;
  std::vector<std::uint32_t> reshaped;  // bricks whose leaf nodes changed
  UpdateBatch::BrickUpdates merged;     // union of one brick's updates from several batches
  BrickMask graded_miss;                // the same for graded scans: miss masks or-ed...
  std::vector<GradedCell> graded_cells;  // ...and cells merged, the larger change kept
  std::vector<float> values;            // brick-local cell -> log-odds, for a rebuild
  std::vector<LeafEntry> rebuilt;
  // The reshaped bricks' leaf-node boxes, taken while their leaves are in the cache: a rebuild
  // of the upper tree reads them instead of every leaf again.
  std::vector<LocalBox> node_boxes;
  std::vector<std::uint32_t> reshaped_boxes;  // first of each reshaped brick's boxes
  std::int64_t leaf_delta = 0;
  InsertStats stats;

  /// Ready for a new batch.
  void reset();
  std::size_t memoryBytes() const;
};

/// Applies a brick's updates (occupied winning over free) to the leaves of brick `slot`. The
/// upper tree is not touched: the brick is recorded in ctx.reshaped if its leaf nodes changed.
void applyBrick(MapStore& store, const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx);

/// Applies graded changes (each cell once) and, if `miss` is given, the miss change to the cells of
/// that mask (a cell in both takes the larger change) to brick `slot`, counting a positive change
/// occupied, others free. The brick is covered anew with boxes of equal mergeable value, as a
/// brick with many updates is. The upper tree is not touched: the brick is recorded in ctx.reshaped.
void applyGradedBrick(MapStore& store, const GradedCell* cells, std::size_t n, const BrickMask* miss,
                      std::uint32_t slot, ApplyContext& ctx);

/// A brick's leaves painted into a dense table of values (kBrickCells); `known` gets their cells.
void loadDense(const std::vector<LeafEntry>& leaves, std::vector<float>& value, BrickMask& known);
/// Brick `slot` covered anew from a dense table (`changed`: the cells that changed, for the count
/// of split leaves), with boxes of equal mergeable value; recorded in ctx.reshaped.
void coverDense(MapStore& store, std::uint32_t slot, const std::vector<float>& value, const BrickMask& known,
                const BrickMask& changed, ApplyContext& ctx);

/// Records brick `slot` as reshaped, with its leaf-node boxes.
void noteReshaped(const MapStore& store, std::uint32_t slot, ApplyContext& ctx);

}  // namespace rtog
