// Absolute values applied to the map (UpdateSet::Kind::Assigned), brick by brick.
#include <algorithm>

#include "integrate/batch_apply.hpp"
#include "integrate/insert_scratch.hpp"

namespace rtog {

void applyAssigned(MapStore& store, const std::vector<AssignedPiece>& pieces, InsertStats& stats,
                   std::vector<ApplyContext>& contexts) {
  LeafIndex& index = store.index;
  // A map without leaves takes the pieces as its leaves, one bulk load of the upper tree after
  // (as a map read from a file); else each touched brick is covered anew, as insertion does.
  const bool fresh = index.leafCount() == 0;
  if (contexts.empty()) contexts.resize(1);
  ApplyContext& ctx = contexts[0];
  ctx.reset();
  std::vector<std::int32_t>& local = ctx.local;
  local.assign(kBrickCells, -1);
  const float l0 = store.model.prior();
  for (std::size_t first = 0; first < pieces.size();) {
    std::size_t last = first;
    while (last < pieces.size() && pieces[last].brick == pieces[first].brick) ++last;
    if (!store.ownsBrick(pieces[first].brick)) {  // outside the map's region: passed over
      first = last;
      continue;
    }
    const std::uint32_t slot = index.brickSlot(pieces[first].brick);
    std::vector<LeafEntry>& leaves = index.mutableBrick(slot).leaves;
    for (std::size_t i = first; i < last; ++i)
      pieces[i].leaf.forEachCell([&](int) { ++(pieces[i].leaf.value > l0 ? ctx.stats.cells_occupied : ctx.stats.cells_free); });
    if (leaves.empty()) {
      for (std::size_t i = first; i < last; ++i) {
        const LeafEntry& e = pieces[i].leaf;
        if ((e.lo[0] == e.hi[0] && e.lo[1] == e.hi[1] && e.lo[2] == e.hi[2]) || store.mergeable(e.value)) {
          leaves.push_back(e);
          continue;
        }
        e.forEachCell([&](int c) {  // a value kept apart by the merge policy: cell by cell
          const auto u = static_cast<std::uint8_t>(c & (kBrickSize - 1)), v = static_cast<std::uint8_t>((c >> kBrickBits) & (kBrickSize - 1)),
                     w = static_cast<std::uint8_t>(c >> (2 * kBrickBits));
          const std::uint8_t lo[3] = {u, v, w};
          leaves.push_back(makeLeaf(lo, lo, e.value));
        });
      }
      for (std::size_t i = 0; i < leaves.size(); ++i)
        leaves[i].forEachCell([&](int c) { local[static_cast<std::size_t>(c)] = static_cast<std::int32_t>(i); });
      const auto created = static_cast<std::int64_t>(leaves.size());
      index.packLeaves(slot, local);
      std::fill(local.begin(), local.end(), -1);
      ctx.stats.leaves_created += static_cast<std::uint64_t>(created);
      ctx.leaf_delta += created;
      if (!fresh) noteReshaped(store, slot, ctx);
    } else {
      BrickMask known, changed{};
      loadDense(leaves, ctx.values, known);
      for (std::size_t i = first; i < last; ++i)
        pieces[i].leaf.forEachCell([&](int c) {
          const auto idx = static_cast<std::size_t>(c);
          ctx.values[idx] = pieces[i].leaf.value;
          known[idx >> 6] |= std::uint64_t{1} << (idx & 63);
          changed[idx >> 6] |= std::uint64_t{1} << (idx & 63);
        });
      coverDense(store, slot, ctx.values, known, changed, ctx);
    }
    first = last;
  }
  if (fresh) {
    stats += ctx.stats;
    index.addLeafCount(ctx.leaf_delta);
    index.rebuildUpperTree();
  } else {
    refreshFromContexts(index, contexts, 1, stats);
  }
}

}  // namespace rtog
