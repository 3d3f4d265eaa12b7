// The planar cache: z-layers of bricks as dense tables of log-odds, updated in place by planar
// scans (2D range scans) until cover() turns each cached brick's layers into leaves again.
// Costs O(updated cells) per scan instead of O(leaves in the touched bricks).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "integrate/graded_scan.hpp"
#include "integrate/planar/planar_batch.hpp"
#include "integrate/planar/step_codec.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/stats.hpp"
#include "storage/map_store.hpp"
#include "util/chunked_vector.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

/// How a cached layer holds its cells.
enum class LayerForm : std::uint8_t {
  Floats,      ///< in `known` and `value`
  Codes,       ///< in `code`, of the cache's StepCodec (`known` and `value` stale)
  OffLattice,  ///< in `known` and `value`, some of them off the StepCodec's lattice
};

struct PlanarLayer {
  std::uint32_t slot;  // brick
  int z;               // brick-local z of the layer
  LayerForm form;
  std::uint32_t floats;  // its values in the cache's float tables (the prior where unknown), if any
  LayerMask known;
  std::array<std::int8_t, kLayerCells> code;
};

/// Whether every cell of `scans` (graded cells and miss masks) lies in one z-layer, and which:
/// false for scans of no cell.
bool gradedLayer(const std::vector<const GradedScan*>& scans, std::int32_t& z);

class PlanarCache {
 public:
  bool empty() const { return layers_.empty(); }
  /// Forgets every cached layer (the map's leaves were cleared).
  void clear();
  std::size_t memoryBytes() const {
    return layers_.capacity() * sizeof(PlanarLayer) + floats_.capacity() * sizeof(LayerValues) + index_.memoryBytes();
  }

  /// Applies the union of batches[0 .. count) of a scan in z-layer `z` (occupied winning).
  void apply(MapStore& store, const std::vector<PlanarBatch>& batches, std::size_t count, int z, InsertStats& stats);
  /// Applies the union of graded scans whose cells all lie in z-layer `z` (gradedLayer), as the
  /// graded applier does (planar_graded.cpp).
  void applyGradedLayer(MapStore& store, const std::vector<const GradedScan*>& scans, std::int32_t z, InsertStats& stats);
  /// Applies grid steps in their order (OccupancyMap::applyStepRuns); throws std::out_of_range,
  /// changing nothing, if a cell has no key.
  InsertStats applyStepRuns(MapStore& store, std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                            std::vector<float>* after);
  /// Covers the cached layers with leaves, brick by brick in slot order, and empties the cache.
  InsertStats cover(MapStore& store);

  /// Whether every cached layer is its brick's only one and in codes (a 2D map's usual state):
  /// then coveredLeaves() reads what cover() would make, without covering.
  bool lonesInCodes() const;
  /// If brick `slot` has a cached layer: its leaves as cover() would leave them (in another
  /// order), into `out`, the cache and the map unchanged; false if it has none. Needs lonesInCodes().
  bool coveredLeaves(const MapStore& store, std::uint32_t slot, std::vector<LeafEntry>& out) const;

 private:
  /// The layer of brick `brick` (brick coordinates) at global z, made from its leaves if new;
  /// recent ones skip the brick and layer hash lookups. In floats unless `codes` (then in codes
  /// if its cells are on the codec's lattice).
  PlanarLayer& layerAt(MapStore& store, const Key& brick, std::int32_t z, bool codes = false);
  /// Makes `rule` the rule of the coded layers (decoding them first if its codes read otherwise).
  void useRule(const StepRule& rule, float prior);
  /// A coded layer's cells back in floats and known bits.
  void decode(PlanarLayer& layer);
  /// The float values of a layer in floats (a table made on first use: a coded layer has none).
  float* values(PlanarLayer& layer);
  const float* values(const PlanarLayer& layer) const { return floats_[layer.floats].data(); }
  /// The index in layers_ of brick `slot`'s layer z (brick-local), made from its leaves if new
  /// (in codes if `codes` and they are on the codec's lattice).
  std::uint32_t layerIndex(const MapStore& store, std::uint32_t slot, int z, bool codes);

  using LayerValues = std::array<float, kLayerCells>;
  static constexpr std::uint32_t kNoFloats = ~std::uint32_t{0};
  detail::ChunkedVector<PlanarLayer, 64> layers_;
  detail::ChunkedVector<LayerValues, 64> floats_;
  detail::FlatHashMap64 index_;            // brick slot * kBrickSize + z -> index in layers_
  detail::RecentLookups<10> recent_;       // packKey(brick x, y, cell z) -> layers_ index
  bool have_rule_ = false;
  StepRule rule_;                          // the last rule of applyStepRuns, with its prior
  float rule_prior_ = 0.0f;
  StepCodec codec_;                        // its codec: the codes of the coded layers
};

}  // namespace rtog
