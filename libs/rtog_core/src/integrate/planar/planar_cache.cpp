#include "integrate/planar/planar_cache.hpp"

#include <algorithm>

#include "kernels/layer_update.hpp"
#include "storage/box_cover.hpp"
#include "storage/morton_order.hpp"

namespace rtog {

using detail::coverGreedily;
using detail::coverLayer;

void PlanarCache::clear() {
  layers_.clear();
  index_.clear();
  recent_.clear();
}

PlanarLayer& PlanarCache::layerAt(MapStore& store, const Key& brick, std::int32_t z) {
  return layers_[recent_.get(packKey(Key{brick.x, brick.y, z}),
                             [&] { return layerIndex(store, store.index.brickSlot(brick), z & (kBrickSize - 1)); })];
}

std::uint32_t PlanarCache::layerIndex(const MapStore& store, std::uint32_t slot, int z) {
  const auto next = static_cast<std::uint32_t>(layers_.size());
  const std::uint32_t index = index_.findOrInsert(std::uint64_t{slot} * kBrickSize + static_cast<std::uint64_t>(z), next);
  if (index != next) return index;
  PlanarLayer& layer = layers_.emplaceBack();
  layer.slot = slot;
  layer.z = z;
  layer.known.fill(0);
  layer.value.fill(store.model.prior());
  // The layer's cells as the leaves crossing it hold them.
  for (const LeafEntry& e : store.index.brick(slot).leaves) {
    if (z < e.lo[2] || z > e.hi[2]) continue;
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
      const int base = y * kBrickSize;
      for (int x = e.lo[0]; x <= e.hi[0]; ++x) layer.value[static_cast<std::size_t>(base + x)] = e.value;
      layer.known[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
    }
  }
  return next;
}

void PlanarCache::apply(MapStore& store, const std::vector<PlanarBatch>& planar_batches, std::size_t batches, int z,
                        InsertStats& stats) {
  const LogOddsModel& model = store.model;
  const PlanarBatch& b0 = planar_batches[0];
  const float deltas[4] = {model.hitDelta(), model.missDelta(), model.clampMin(), model.clampMax()};
  static const detail::UpdateLayerFn update_layer = [] {
    const auto kernels = detail::layerUpdateKernels();
    return kernels[1] ? kernels[1] : kernels[0];
  }();
  detail::LayerCounts counts;
  for (std::size_t t = 0; t < b0.tiles().size(); ++t) {
    // The union over the threads' batches, occupied winning.
    PlanarBatch::Tile tile = b0.tiles()[t];
    for (std::size_t k = 1; k < batches; ++k)
      for (int w = 0; w < kLayerWords; ++w) {
        tile.occupied[static_cast<std::size_t>(w)] |= planar_batches[k].tiles()[t].occupied[static_cast<std::size_t>(w)];
        tile.free[static_cast<std::size_t>(w)] |= planar_batches[k].tiles()[t].free[static_cast<std::size_t>(w)];
      }
    std::uint64_t any = 0;
    for (int w = 0; w < kLayerWords; ++w) any |= tile.occupied[static_cast<std::size_t>(w)] | tile.free[static_cast<std::size_t>(w)];
    if (any == 0) continue;
    const auto width = static_cast<std::size_t>(b0.width());
    const Key brick{b0.brickX0() + static_cast<int>(t % width), b0.brickY0() + static_cast<int>(t / width),
                    z >> kBrickBits};
    // Most of a scan's tiles were layers of the scans before: recent ones skip the brick and
    // layer hash lookups.
    PlanarLayer& layer = layerAt(store, brick, z);
    // Unknown cells hold the prior, so a first update is an update like any other.
    update_layer(layer.value.data(), layer.known.data(), tile.occupied.data(), tile.free.data(), deltas, counts);
  }
  stats.cells_unchanged += counts.unchanged;
  stats.cells_free += counts.free;
  stats.cells_occupied += counts.occupied;
}

InsertStats PlanarCache::cover(MapStore& store) {
  LeafIndex& index = store.index;
  InsertStats stats;
  if (layers_.empty()) return stats;
  // A brick's layers together, bricks in slot order (deterministic whatever the scans' order).
  std::vector<std::uint32_t> order(layers_.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const PlanarLayer &la = layers_[a], &lb = layers_[b];
    return la.slot != lb.slot ? la.slot < lb.slot : la.z < lb.z;
  });
  std::vector<LeafEntry> out;
  std::vector<std::uint32_t> reshaped;
  for (std::size_t i = 0; i < order.size();) {
    const std::uint32_t slot = layers_[order[i]].slot;
    const PlanarLayer* layer_at[kBrickSize] = {};
    BrickMask known{};
    int layers = 0;
    for (; i < order.size() && layers_[order[i]].slot == slot; ++i, ++layers) {
      const PlanarLayer& layer = layers_[order[i]];
      layer_at[layer.z] = &layer;
      std::copy(layer.known.begin(), layer.known.end(), known.begin() + layer.z * kLayerWords);
    }
    // Leaves outside the cached layers stay; those crossing them keep their parts outside.
    std::vector<LeafEntry>& leaves = index.brick(slot).leaves;
    out.clear();
    for (const LeafEntry& e : leaves) {
      bool crosses = false;
      for (int z = e.lo[2]; z <= e.hi[2] && !crosses; ++z) crosses = layer_at[z] != nullptr;
      if (!crosses) {
        out.push_back(e);
        continue;
      }
      for (int z = e.lo[2]; z <= e.hi[2]; ++z) {
        if (layer_at[z]) continue;
        int z1 = z;
        while (z1 + 1 <= e.hi[2] && !layer_at[z1 + 1]) ++z1;
        LeafEntry piece = e;
        piece.lo[2] = static_cast<std::uint8_t>(z);
        piece.hi[2] = static_cast<std::uint8_t>(z1);
        out.push_back(piece);
        ++stats.leaves_created;
        z = z1;
      }
      ++stats.leaves_merged;
    }
    const auto valueAt = [&](int cell) { return layer_at[cell / kLayerCells]->value[static_cast<std::size_t>(cell % kLayerCells)]; };
    const std::size_t kept = out.size();
    if (layers == 1) {
      const PlanarLayer& layer = layers_[order[i - 1]];
      coverLayer(
          layer.known, layer.value.data(), layer.z, [&](float v) { return store.mergeable(v); },
          [&](const std::uint8_t lo[3], const std::uint8_t hi[3], float v) {
            out.push_back(makeLeaf(lo, hi, v));
          });
    } else {
      coverGreedily(
          known,
          [&](int start, int cell) {
            const float v = valueAt(start);
            return valueAt(cell) == v && store.mergeable(v);
          },
          [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
            out.push_back(makeLeaf(lo, hi, valueAt(start)));
          });
    }
    stats.leaves_created += out.size() - kept;
    index.addLeafCount(static_cast<std::int64_t>(out.size()) - static_cast<std::int64_t>(leaves.size()));
    assignByFirstCell(out, leaves);
    reshaped.push_back(slot);
  }
  index.refreshUpperTree(reshaped);
  // Keep room for the layers of a scan or two (a 2D scan at 5 cm touches about 200), not for
  // those of a whole log: the pool counts in memoryBytes().
  constexpr std::size_t kKeptLayers = 512;
  recent_.clear();
  if (layers_.capacity() > kKeptLayers) {
    layers_.release();
    index_ = detail::FlatHashMap64();
  } else {
    layers_.clear();
    index_.clear();
  }
  return stats;
}

}  // namespace rtog
