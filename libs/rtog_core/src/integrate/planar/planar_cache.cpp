#include "integrate/planar/planar_cache.hpp"

#include <algorithm>
#include <cstring>

#include "kernels/layer_update.hpp"
#include "kernels/row_compare.hpp"
#include "storage/box_cover.hpp"
#include "storage/morton_order.hpp"

namespace rtog {

using detail::coverRows;
using detail::coverLayer;

void PlanarCache::clear() {
  layers_.clear();
  floats_.clear();
  index_.clear();
  recent_.clear();
}

float* PlanarCache::values(PlanarLayer& layer) {
  if (layer.floats == kNoFloats) {
    layer.floats = static_cast<std::uint32_t>(floats_.size());
    floats_.emplaceBack();
  }
  return floats_[layer.floats].data();
}

PlanarLayer& PlanarCache::layerAt(MapStore& store, const Key& brick, std::int32_t z, bool codes) {
  PlanarLayer& layer =
      layers_[recent_.get(packKey(Key{brick.x, brick.y, z}),
                          [&] { return layerIndex(store, store.index.brickSlot(brick), z & (kBrickSize - 1), codes); })];
  if (codes && layer.form == LayerForm::Floats) {
    // Into codes, or marked off the lattice (a cell of another rule) and stepped in floats.
    std::array<std::int8_t, kLayerCells> code;
    const float* value = values(layer);
    bool on = true;
    for (int i = 0; i < kLayerCells && on; ++i) {
      const bool known = (layer.known[static_cast<std::size_t>(i >> 6)] >> (i & 63)) & 1u;
      if (known)
        on = codec_.encode(value[i], code[static_cast<std::size_t>(i)]);
      else
        code[static_cast<std::size_t>(i)] = StepCodec::kUnknown;
    }
    if (on) layer.code = code;
    layer.form = on ? LayerForm::Codes : LayerForm::OffLattice;
  } else if (!codes && layer.form == LayerForm::Codes) {
    decode(layer);
  }
  return layer;
}

void PlanarCache::decode(PlanarLayer& layer) {
  layer.known.fill(0);
  float* const value = values(layer);
  for (int i = 0; i < kLayerCells; ++i) {
    const std::int8_t c = layer.code[static_cast<std::size_t>(i)];
    value[i] = codec_.value(c);
    if (c != StepCodec::kUnknown) layer.known[static_cast<std::size_t>(i >> 6)] |= std::uint64_t{1} << (i & 63);
  }
  layer.form = LayerForm::Floats;
}

namespace {

/// StepCodec::make(rule, prior), kept for the thread's last 256 rules: graded scans (range noise
/// and pose blur in the mrpt_grid preset) apply a rule for each step size they use, mostly the
/// same sizes scan after scan, and a codec is 768 steps to make. Per thread, not per map: a
/// particle filter's maps would each hold the same codecs (about 1 MiB at most).
StepCodec madeCodec(const StepRule& rule, float prior) {
  struct Made {
    StepRule rule;
    float prior;
    StepCodec codec;
  };
  constexpr std::size_t kKept = 256;
  thread_local std::vector<Made> made;
  thread_local std::size_t next = 0;  // the entry to replace once `made` is full
  for (const Made& m : made)
    if (std::memcmp(&rule, &m.rule, sizeof rule) == 0 && prior == m.prior) return m.codec;
  const StepCodec codec = StepCodec::make(rule, prior);
  if (made.size() < kKept) made.push_back(Made{rule, prior, codec});
  else made[next] = Made{rule, prior, codec}, next = (next + 1) % kKept;
  return codec;
}

}  // namespace

void PlanarCache::useRule(const StepRule& rule, float prior) {
  if (have_rule_ && std::memcmp(&rule, &rule_, sizeof rule) == 0 && prior == rule_prior_) return;
  StepCodec fresh = madeCodec(rule, prior);
  if (codec_.usable() && !(fresh.usable() && fresh.sameCodes(codec_)))
    for (std::size_t i = 0; i < layers_.size(); ++i)
      if (layers_[i].form == LayerForm::Codes) decode(layers_[i]);
  have_rule_ = true;
  rule_ = rule;
  rule_prior_ = prior;
  codec_ = fresh;
}

std::uint32_t PlanarCache::layerIndex(const MapStore& store, std::uint32_t slot, int z, bool codes) {
  const auto next = static_cast<std::uint32_t>(layers_.size());
  const std::uint32_t index = index_.findOrInsert(std::uint64_t{slot} * kBrickSize + static_cast<std::uint64_t>(z), next);
  if (index != next) return index;
  PlanarLayer& layer = layers_.emplaceBack();
  layer.slot = slot;
  layer.z = z;
  layer.floats = kNoFloats;
  const std::vector<LeafEntry>& leaves = store.index.brick(slot).leaves;
  const auto crosses = [z](const LeafEntry& e) { return z >= e.lo[2] && z <= e.hi[2]; };
  if (codes) {
    // In codes straight from the leaves (a code a leaf), unless a leaf is off the lattice.
    layer.code.fill(StepCodec::kUnknown);
    bool on = true;
    for (std::size_t i = 0; i < leaves.size() && on; ++i) {
      const LeafEntry& e = leaves[i];
      std::int8_t c = 0;
      if (!crosses(e)) continue;
      if (!(on = codec_.encode(e.value, c))) break;
      for (int y = e.lo[1]; y <= e.hi[1]; ++y)
        std::fill_n(layer.code.begin() + y * kBrickSize + e.lo[0], e.hi[0] - e.lo[0] + 1, c);
    }
    if (on) {
      layer.form = LayerForm::Codes;
      return next;
    }
  }
  layer.form = codes ? LayerForm::OffLattice : LayerForm::Floats;
  layer.known.fill(0);
  float* const value = values(layer);
  std::fill_n(value, kLayerCells, store.model.prior());
  // The layer's cells as the leaves crossing it hold them.
  for (const LeafEntry& e : leaves) {
    if (!crosses(e)) continue;
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
      const int base = y * kBrickSize;
      for (int x = e.lo[0]; x <= e.hi[0]; ++x) value[base + x] = e.value;
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
  const detail::UpdateLayerFn update_layer = detail::bestLayerUpdate();
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
    if (!store.ownsBrick(brick)) continue;
    // Most of a scan's tiles were layers of the scans before: recent ones skip the brick and
    // layer hash lookups.
    PlanarLayer& layer = layerAt(store, brick, z);
    // Unknown cells hold the prior, so a first update is an update like any other.
    update_layer(values(layer), layer.known.data(), tile.occupied.data(), tile.free.data(), deltas, counts);
  }
  stats.cells_unchanged += counts.unchanged;
  stats.cells_free += counts.free;
  stats.cells_occupied += counts.occupied;
}

namespace {

/// The known cells of a coded layer (every code but kUnknown).
LayerMask knownOfCodes(const std::array<std::int8_t, kLayerCells>& code) {
  LayerMask known{};
  for (int y = 0; y < kBrickSize; ++y) {
    const std::uint64_t row = ~detail::equalMask16(code.data() + y * kBrickSize, StepCodec::kUnknown) & 0xFFFFu;
    known[static_cast<std::size_t>(y / 4)] |= row << ((y % 4) * kBrickSize);
  }
  return known;
}

/// The brick's leaves that lie outside its cached layers, whole or in parts (those crossing a
/// cached layer keep their parts outside it), appended to `out`; returns the leaves cut.
std::size_t leavesOutside(const std::vector<LeafEntry>& leaves, const PlanarLayer* const (&layer_at)[kBrickSize],
                          std::vector<LeafEntry>& out, InsertStats* stats) {
  std::size_t cut = 0;
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
      if (stats) ++stats->leaves_created;
      z = z1;
    }
    ++cut;
  }
  return cut;
}

/// The leaves of a lone coded layer whose known cells are `known`, appended to `out`.
void coverCodes(const MapStore& store, const StepCodec& codec, const PlanarLayer& layer, const LayerMask& known,
                std::vector<LeafEntry>& out) {
  coverLayer(
      known, layer.code.data(), layer.z, [&](std::int8_t c) { return store.mergeable(codec.value(c)); },
      [&](const std::uint8_t lo[3], const std::uint8_t hi[3], std::int8_t c) {
        appendLeaf(out, lo, hi, codec.value(c));
      });
}

}  // namespace

bool PlanarCache::lonesInCodes() const {
  std::vector<std::uint32_t> slots(layers_.size());
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    if (layers_[i].form != LayerForm::Codes) return false;
    slots[i] = layers_[i].slot;
  }
  std::sort(slots.begin(), slots.end());
  return std::adjacent_find(slots.begin(), slots.end()) == slots.end();
}

bool PlanarCache::coveredLeaves(const MapStore& store, std::uint32_t slot, std::vector<LeafEntry>& out) const {
  out.clear();
  const PlanarLayer* layer_at[kBrickSize] = {};
  const PlanarLayer* layer = nullptr;
  for (int z = 0; z < kBrickSize && !layer; ++z) {
    const std::uint32_t i = index_.find(std::uint64_t{slot} * kBrickSize + static_cast<std::uint64_t>(z));
    if (i != detail::FlatHashMap64::kAbsent) layer = layer_at[z] = &layers_[i];
  }
  if (!layer) return false;
  leavesOutside(store.index.brick(slot).leaves, layer_at, out, nullptr);
  coverCodes(store, codec_, *layer, knownOfCodes(layer->code), out);
  return true;
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
    std::size_t end = i;
    while (end < order.size() && layers_[order[end]].slot == slot) ++end;
    // A lone coded layer is covered in its codes; layers covered together, in floats.
    const bool lone_codes = end == i + 1 && layers_[order[i]].form == LayerForm::Codes;
    if (lone_codes) {
      PlanarLayer& layer = layers_[order[i]];
      layer.known = knownOfCodes(layer.code);
    } else {
      for (std::size_t k = i; k < end; ++k)
        if (layers_[order[k]].form == LayerForm::Codes) decode(layers_[order[k]]);
    }
    int layers = 0;
    for (; i < end; ++i, ++layers) {
      const PlanarLayer& layer = layers_[order[i]];
      layer_at[layer.z] = &layer;
      std::copy(layer.known.begin(), layer.known.end(), known.begin() + layer.z * kLayerWords);
    }
    // Leaves outside the cached layers stay; those crossing them keep their parts outside.
    std::vector<LeafEntry>& leaves = index.mutableBrick(slot).leaves;
    out.clear();
    stats.leaves_merged += leavesOutside(leaves, layer_at, out, &stats);
    const auto valueAt = [&](int cell) { return values(*layer_at[cell / kLayerCells])[cell % kLayerCells]; };
    const std::size_t kept = out.size();
    if (lone_codes) {
      const PlanarLayer& layer = layers_[order[i - 1]];
      coverCodes(store, codec_, layer, layer.known, out);
    } else if (layers == 1) {
      const PlanarLayer& layer = layers_[order[i - 1]];
      coverLayer(
          layer.known, values(layer), layer.z, [&](float v) { return store.mergeable(v); },
          [&](const std::uint8_t lo[3], const std::uint8_t hi[3], float v) {
            appendLeaf(out, lo, hi, v);
          });
    } else {
      // Several cached layers: a row's values are its layer's.
      coverRows(
          known,
          [&](std::uint32_t row, int start, int y, int z) -> std::uint32_t {
            const float v = valueAt(start);
            if (row == 0 || !store.mergeable(v)) return 0;
            return row & detail::equalMask16(values(*layer_at[z]) + y * kBrickSize, v);
          },
          [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
            appendLeaf(out, lo, hi, valueAt(start));
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
  if (floats_.capacity() > kKeptLayers)
    floats_.release();
  else
    floats_.clear();
  return stats;
}

}  // namespace rtog
