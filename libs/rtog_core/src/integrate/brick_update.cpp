#include "integrate/brick_update.hpp"

#include <algorithm>

#include "storage/box_cover.hpp"
#include "storage/morton_order.hpp"

namespace rtog {

using detail::coverGreedily;
using detail::coverValues;

/// applyBrick()'s way for a brick without leaves under equal-value merging: each class of
/// fresh cells has one value, so the greedy cover of each class's mask gives the leaves, the
/// same boxes as rebuildBrick()'s cover (which never joins cells of different values).
// Out of line: inlined into applyBrick(), the cover ran 19 % more instructions (callgrind, VLP-16).
[[gnu::noinline]] static void coverFreshBrick(MapStore& store, const UpdateBatch::BrickUpdates& upd,
                                              std::uint32_t slot, ApplyContext& ctx);
/// applyBrick()'s way for a brick with many updates: values into a dense table, updated
/// there, and the brick covered anew with boxes of equal (mergeable) value. Costs O(4096)
/// instead of a split and merges per updated cell.
static void rebuildBrick(MapStore& store, const UpdateBatch::BrickUpdates& upd, std::uint32_t slot,
                         ApplyContext& ctx);
static std::size_t mergeInBrick(const MapStore& store, std::vector<LeafEntry>& leaves,
                                std::vector<std::int32_t>& local, const std::vector<std::uint32_t>& candidates);

std::size_t ApplyContext::memoryBytes() const {
  return sizeof(*this) + local.capacity() * sizeof(std::int32_t) + candidates.capacity() * sizeof(std::uint32_t) +
         reshaped.capacity() * sizeof(std::uint32_t) + values.capacity() * sizeof(float) +
         rebuilt.capacity() * sizeof(LeafEntry) + node_boxes.capacity() * sizeof(LocalBox) +
         reshaped_boxes.capacity() * sizeof(std::uint32_t) + graded_cells.capacity() * sizeof(GradedCell);
}

void ApplyContext::reset() {
  local.assign(kBrickCells, -1);
  reshaped.clear();
  node_boxes.clear();
  reshaped_boxes.clear();
  leaf_delta = 0;
  stats = InsertStats{};
}

namespace {

// Cuts `box` (brick-local, inclusive) around `cell` into at most six boxes that cover
// box minus cell: x-slabs first, then y-rows, then z-runs.
int cutAround(const std::uint8_t lo[3], const std::uint8_t hi[3], const Key& cell, std::uint8_t out_lo[6][3],
              std::uint8_t out_hi[6][3]) {
  int n = 0;
  std::uint8_t cur_lo[3] = {lo[0], lo[1], lo[2]}, cur_hi[3] = {hi[0], hi[1], hi[2]};
  for (int a = 0; a < 3; ++a) {
    const auto c = static_cast<std::uint8_t>(cell[a]);
    if (c > cur_lo[a]) {
      std::copy(cur_lo, cur_lo + 3, out_lo[n]);
      std::copy(cur_hi, cur_hi + 3, out_hi[n]);
      out_hi[n][a] = static_cast<std::uint8_t>(c - 1);
      ++n;
    }
    if (c < cur_hi[a]) {
      std::copy(cur_lo, cur_lo + 3, out_lo[n]);
      std::copy(cur_hi, cur_hi + 3, out_hi[n]);
      out_lo[n][a] = static_cast<std::uint8_t>(c + 1);
      ++n;
    }
    cur_lo[a] = cur_hi[a] = c;
  }
  return n;
}

}  // namespace

void noteReshaped(const MapStore& store, std::uint32_t slot, ApplyContext& ctx) {
  const std::vector<LeafEntry>& leaves = store.index.brick(slot).leaves;
  ctx.reshaped.push_back(slot);
  ctx.reshaped_boxes.push_back(static_cast<std::uint32_t>(ctx.node_boxes.size()));
  for (std::size_t k = 0; k * store.index.leafNodeSize() < leaves.size(); ++k) ctx.node_boxes.push_back(store.index.localNodeBox(leaves, k));
}

namespace {

// Writes `leaf` into the scratch table over its box and sets the box's bits in `painted`.
void paintLeaf(const std::uint8_t lo[3], const std::uint8_t hi[3], std::int32_t leaf, std::vector<std::int32_t>& local,
               BrickMask& painted) {
  const std::uint64_t run = xRun(lo[0], hi[0]);
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y) {
      const int base = localIndex(0, y, z);
      for (int x = lo[0]; x <= hi[0]; ++x) local[static_cast<std::size_t>(base + x)] = leaf;
      painted[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
    }
}

}  // namespace

void applyBrick(MapStore& store, const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx) {
  const LogOddsModel& model = store.model;
  std::vector<LeafEntry>& leaves = store.index.mutableBrick(slot).leaves;
  std::vector<std::int32_t>& local = ctx.local;
  InsertStats& stats = ctx.stats;
  const std::size_t updates_occupied = maskPopcount(upd.occupied), updates_free = maskPopcount(upd.free);
  stats.cells_occupied += updates_occupied;
  stats.cells_free += updates_free;
  // Past this many updates one pass over the brick beats splitting and re-merging per cell
  // (measured on the TUM frames). Only equal-value merging churns so: clamped cuboids absorb
  // most updates unchanged.
  constexpr std::size_t kRebuildUpdates = 128;
  if (store.params.merge == MergePolicy::Equal && leaves.empty()) {
    coverFreshBrick(store, upd, slot, ctx);
    return;
  }
  if (store.params.merge == MergePolicy::Equal && updates_occupied + updates_free >= kRebuildUpdates) {
    rebuildBrick(store, upd, slot, ctx);
    return;
  }
  BrickMask known{};
  for (std::size_t i = 0; i < leaves.size(); ++i)
    paintLeaf(leaves[i].lo, leaves[i].hi, static_cast<std::int32_t>(i), local, known);

  const bool merging = store.params.merge != MergePolicy::Off;
  const std::size_t leaves_before = leaves.size();
  bool reshaped = false;
  std::vector<std::uint32_t>& candidates = ctx.candidates;
  candidates.clear();
  // Cells seen for the first time: all of a class get the same value, so they go in as boxes.
  const auto addFresh = [&](const BrickMask& mask, float delta) {
    const float v = model.first(delta);
    const bool boxes = merging && store.mergeable(v);
    const auto add = [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int /*start*/ = 0) {
      appendLeaf(leaves, lo, hi, v);
      const auto li = static_cast<std::int32_t>(leaves.size() - 1);
      paintLeaf(lo, hi, li, local, known);
      if (boxes) candidates.push_back(static_cast<std::uint32_t>(li));
    };
    if (boxes) {
      coverGreedily(mask, add);
      return;
    }
    for (int w = 0; w < kBrickWords; ++w)
      for (std::uint64_t bits = mask[static_cast<std::size_t>(w)]; bits; bits &= bits - 1) {
        const Key lk = localKey(w * 64 + __builtin_ctzll(bits));
        const std::uint8_t c[3] = {static_cast<std::uint8_t>(lk.x), static_cast<std::uint8_t>(lk.y),
                                   static_cast<std::uint8_t>(lk.z)};
        add(c, c);
      }
  };
  BrickMask fresh_occ, fresh_free;
  for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w) {
    fresh_occ[w] = upd.occupied[w] & ~known[w];
    fresh_free[w] = upd.free[w] & ~upd.occupied[w] & ~known[w];
  }
  for (int w = 0; w < kBrickWords; ++w) {
    std::uint64_t bits = (upd.occupied[w] | upd.free[w]) & known[w];
    while (bits) {
      const int b = __builtin_ctzll(bits);
      bits &= bits - 1;
      const int idx = w * 64 + b;
      const float delta = (upd.occupied[w] >> b) & 1u ? model.hitDelta() : model.missDelta();
      const Key lk = localKey(idx);
      const std::int32_t li = local[idx];
      LeafEntry& e = leaves[static_cast<std::size_t>(li)];
      const float old = e.value;
      const float v = model.update(old, delta);
      if (v == old) {
        ++stats.cells_unchanged;
        continue;
      }
      e.value = v;
      if (merging && store.mergeable(v)) candidates.push_back(static_cast<std::uint32_t>(li));
      if (e.lo[0] == e.hi[0] && e.lo[1] == e.hi[1] && e.lo[2] == e.hi[2]) continue;

      // Disagreeing evidence inside a merged cuboid: the leaf shrinks to the updated cell
      // and the rest of its cells keep the old value in at most six new leaves.
      std::uint8_t plo[6][3], phi[6][3];
      const LeafEntry whole = e;
      const int pieces = cutAround(whole.lo, whole.hi, lk, plo, phi);
      for (int a = 0; a < 3; ++a) e.lo[a] = e.hi[a] = static_cast<std::uint8_t>(lk[a]);
      for (int p = 0; p < pieces; ++p) {
        leaves.push_back(makeLeaf(plo[p], phi[p], old));
        const auto pi = static_cast<std::int32_t>(leaves.size() - 1);
        leaves.back().forEachCell([&](int i) { local[static_cast<std::size_t>(i)] = pi; });
        candidates.push_back(static_cast<std::uint32_t>(pi));  // was merged, so mergeable
      }
      ++stats.leaves_split;
      reshaped = true;
    }
  }
  addFresh(fresh_occ, model.hitDelta());
  addFresh(fresh_free, model.missDelta());
  stats.leaves_created += leaves.size() - leaves_before;
  if (merging && !candidates.empty()) {
    const std::size_t merges = mergeInBrick(store, leaves, local, candidates);
    stats.leaves_merged += merges;
    reshaped |= merges > 0;
  }
  if (reshaped || leaves.size() != leaves_before) {
    // Leaves merged away are replaced by the last ones, new leaves were appended: only the
    // leaf nodes at those places change, and syncLeafNodes() updates just those boxes.
    for (std::size_t i = 0; i < leaves.size();) {
      if (leaves[i].lo[0] == kDead) {
        leaves[i] = leaves.back();
        leaves.pop_back();
      } else {
        ++i;
      }
    }
    if (leaves.capacity() > 2 * leaves.size() + 16) leaves.shrink_to_fit();
    noteReshaped(store, slot, ctx);
  }
  ctx.leaf_delta += static_cast<std::int64_t>(leaves.size()) - static_cast<std::int64_t>(leaves_before);
  // Leave the scratch table empty for the next brick; only painted cells need it.
  for (const LeafEntry& e : leaves) e.forEachCell([&](int idx) { local[idx] = -1; });
}

static void coverFreshBrick(MapStore& store, const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx) {
  const LogOddsModel& model = store.model;
  std::vector<LeafEntry>& out = ctx.rebuilt;
  out.clear();
  for (const bool occupied : {true, false}) {
    const float v = model.first(occupied ? model.hitDelta() : model.missDelta());
    coverGreedily(
        occupied ? upd.occupied : upd.free,
        [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int) {
          appendLeaf(out, lo, hi, v);
        });
  }
  ctx.stats.leaves_created += out.size();
  ctx.leaf_delta += static_cast<std::int64_t>(out.size());
  assignByFirstCell(out, store.index.mutableBrick(slot).leaves);
  noteReshaped(store, slot, ctx);
}

// The brick's leaves painted into a dense table of values; `known` gets their cells.
void loadDense(const std::vector<LeafEntry>& leaves, std::vector<float>& value, BrickMask& known) {
  value.resize(kBrickCells);
  known = BrickMask{};
  for (const LeafEntry& e : leaves) {
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    for (int z = e.lo[2]; z <= e.hi[2]; ++z)
      for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
        const int base = localIndex(0, y, z);
        for (int x = e.lo[0]; x <= e.hi[0]; ++x) value[static_cast<std::size_t>(base + x)] = e.value;
        known[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
      }
  }
}

namespace {

// One cell's update in the dense table: counted unchanged, or marked changed (and known).
void updateDense(const LogOddsModel& model, std::size_t idx, float delta, std::vector<float>& value, BrickMask& known,
                 BrickMask& changed, InsertStats& stats) {
  const std::size_t w = idx >> 6;
  const std::uint64_t bit = std::uint64_t{1} << (idx & 63);
  if (known[w] & bit) {
    const float v = model.update(value[idx], delta);
    if (v == value[idx]) {
      ++stats.cells_unchanged;
      return;
    }
    value[idx] = v;
  } else {
    value[idx] = model.first(delta);
    known[w] |= bit;
  }
  changed[w] |= bit;
}

}  // namespace

// The brick covered anew from the dense table: old cuboids that now disagree inside are the
// splits; the known cells are covered with boxes of bit-identical (so lossless), mergeable values.
void coverDense(MapStore& store, std::uint32_t slot, const std::vector<float>& value, const BrickMask& known,
                const BrickMask& changed, ApplyContext& ctx) {
  std::vector<LeafEntry>& leaves = store.index.mutableBrick(slot).leaves;
  InsertStats& stats = ctx.stats;
  for (const LeafEntry& e : leaves) {
    if (e.lo[0] == e.hi[0] && e.lo[1] == e.hi[1] && e.lo[2] == e.hi[2]) continue;
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    bool hit = false;
    for (int z = e.lo[2]; z <= e.hi[2] && !hit; ++z)
      for (int y = e.lo[1]; y <= e.hi[1] && !hit; ++y) {
        const int base = localIndex(0, y, z);
        hit = (changed[static_cast<std::size_t>(base >> 6)] >> (base & 63)) & run;
      }
    stats.leaves_split += hit;
  }
  std::vector<LeafEntry>& out = ctx.rebuilt;
  out.clear();
  coverValues(
      known, value.data(), [&](float v) { return store.mergeable(v); },
      [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
        appendLeaf(out, lo, hi, value[static_cast<std::size_t>(start)]);
      });
  stats.leaves_created += out.size();
  stats.leaves_merged += leaves.size();
  ctx.leaf_delta += static_cast<std::int64_t>(out.size()) - static_cast<std::int64_t>(leaves.size());
  assignByFirstCell(out, leaves);
  noteReshaped(store, slot, ctx);
}


static void rebuildBrick(MapStore& store, const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx) {
  const LogOddsModel& model = store.model;
  std::vector<float>& value = ctx.values;
  BrickMask known, changed{};
  loadDense(store.index.brick(slot).leaves, value, known);
  for (int w = 0; w < kBrickWords; ++w) {
    const auto wi = static_cast<std::size_t>(w);
    for (std::uint64_t bits = upd.occupied[wi] | upd.free[wi]; bits; bits &= bits - 1) {
      const int b = __builtin_ctzll(bits);
      const float delta = (upd.occupied[wi] >> b) & 1u ? model.hitDelta() : model.missDelta();
      updateDense(model, static_cast<std::size_t>(w * 64 + b), delta, value, known, changed, ctx.stats);
    }
  }
  coverDense(store, slot, value, known, changed, ctx);
}

void applyGradedBrick(MapStore& store, const GradedCell* cells, std::size_t n, const BrickMask* miss,
                      std::uint32_t slot, ApplyContext& ctx) {
  const LogOddsModel& model = store.model;
  std::vector<float>& value = ctx.values;
  BrickMask known, changed{}, graded{};
  loadDense(store.index.brick(slot).leaves, value, known);
  for (std::size_t i = 0; i < n; ++i) graded[cells[i].local >> 6] |= std::uint64_t{1} << (cells[i].local & 63);
  if (miss)
    for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w)
      for (std::uint64_t bits = (*miss)[w] & ~graded[w]; bits; bits &= bits - 1) {
        ++ctx.stats.cells_free;
        updateDense(model, w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits)), model.missDelta(), value, known,
                    changed, ctx.stats);
      }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t idx = cells[i].local;
    float delta = cells[i].delta;
    if (miss && ((*miss)[idx >> 6] >> (idx & 63) & 1u)) delta = std::max(delta, model.missDelta());
    (delta > 0.0f ? ctx.stats.cells_occupied : ctx.stats.cells_free) += 1;
    updateDense(model, idx, delta, value, known, changed, ctx.stats);
  }
  coverDense(store, slot, value, known, changed, ctx);
}

static std::size_t mergeInBrick(const MapStore& store, std::vector<LeafEntry>& leaves, std::vector<std::int32_t>& local,
                         const std::vector<std::uint32_t>& candidates) {
  std::size_t merges = 0;
  for (const std::uint32_t i : candidates) {
    for (bool merged = true; merged;) {
      merged = false;
      LeafEntry& a = leaves[i];
      if (a.lo[0] == kDead || !store.mergeable(a.value)) break;
      for (int axis = 0; axis < 3 && !merged; ++axis) {
        const int b1 = (axis + 1) % 3, b2 = (axis + 2) % 3;
        for (int dir = 1; dir >= -1 && !merged; dir -= 2) {
          const int c = dir > 0 ? a.hi[axis] + 1 : a.lo[axis] - 1;
          if (c < 0 || c >= kBrickSize) continue;
          int n[3] = {a.lo[0], a.lo[1], a.lo[2]};
          n[axis] = c;
          const std::int32_t j = local[localIndex(n[0], n[1], n[2])];
          if (j < 0 || static_cast<std::uint32_t>(j) == i) continue;
          LeafEntry& nb = leaves[static_cast<std::size_t>(j)];
          // A face neighbour holding the cell next to a's corner starts right after a on
          // this axis (leaves are disjoint); it merges if its face matches exactly.
          if (nb.lo[b1] != a.lo[b1] || nb.hi[b1] != a.hi[b1] || nb.lo[b2] != a.lo[b2] || nb.hi[b2] != a.hi[b2])
            continue;
          if (nb.value != a.value) continue;
          nb.forEachCell([&](int idx) { local[idx] = static_cast<std::int32_t>(i); });
          a.lo[axis] = std::min(a.lo[axis], nb.lo[axis]);
          a.hi[axis] = std::max(a.hi[axis], nb.hi[axis]);
          nb.lo[0] = kDead;
          ++merges;
          merged = true;
        }
      }
    }
  }
  return merges;
}


}  // namespace rtog
