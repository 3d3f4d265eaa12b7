// The planar cache: z-layers of bricks as dense tables of log-odds, updated in place by planar
// scans (2D range scans) until cover() turns each cached brick's layers into leaves again.
// Costs O(updated cells) per scan instead of O(leaves in the touched bricks).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "integrate/planar/planar_batch.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/stats.hpp"
#include "storage/map_store.hpp"
#include "util/chunked_vector.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

struct PlanarLayer {
  std::uint32_t slot;  // brick
  int z;               // brick-local z of the layer
  LayerMask known;
  std::array<float, kLayerCells> value;  // the prior where unknown
};

class PlanarCache {
 public:
  bool empty() const { return layers_.empty(); }
  /// Forgets every cached layer (the map's leaves were cleared).
  void clear();
  std::size_t memoryBytes() const { return layers_.capacity() * sizeof(PlanarLayer) + index_.memoryBytes(); }

  /// Applies the union of batches[0 .. count) of a scan in z-layer `z` (occupied winning).
  void apply(MapStore& store, const std::vector<PlanarBatch>& batches, std::size_t count, int z, InsertStats& stats);
  /// Applies grid steps in their order (OccupancyMap::applyStepRuns); throws std::out_of_range,
  /// changing nothing, if a cell has no key.
  InsertStats applyStepRuns(MapStore& store, std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                            std::vector<float>* after);
  /// Covers the cached layers with leaves, brick by brick in slot order, and empties the cache.
  InsertStats cover(MapStore& store);

 private:
  /// The layer of brick `brick` (brick coordinates) at global z, made from its leaves if new;
  /// recent ones skip the brick and layer hash lookups.
  PlanarLayer& layerAt(MapStore& store, const Key& brick, std::int32_t z);
  /// The index in layers_ of brick `slot`'s layer z (brick-local), made from its leaves if new.
  std::uint32_t layerIndex(const MapStore& store, std::uint32_t slot, int z);

  detail::ChunkedVector<PlanarLayer, 64> layers_;
  detail::FlatHashMap64 index_;            // brick slot * kBrickSize + z -> index in layers_
  detail::RecentLookups<10> recent_;       // packKey(brick x, y, cell z) -> layers_ index
};

}  // namespace rtog
