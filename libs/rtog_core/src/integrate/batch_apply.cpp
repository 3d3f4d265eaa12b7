#include "integrate/batch_apply.hpp"

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <thread>

#include "kernels/row_compare.hpp"
#include "parallel/parallel.hpp"

namespace rtog {
namespace {

// Group g has the updates sources[first[g] .. first[g + 1]) of brick slots[g]. The arrays are
// sized before grouping starts and never move: appliers read the groups published while later
// ones are written. What the grouper writes for every group (count), what the appliers poll
// (published) and the vectors' headers they read for every group lie on cache lines of their own,
// whatever the stack's offset: else each group's write would take the pollers' line away.
struct alignas(64) BrickGroups {
  static constexpr std::size_t kPublishEvery = 16;
  std::vector<const UpdateBatch::BrickUpdates*> sources;
  std::vector<std::uint32_t> first, slots;
  alignas(64) std::atomic<std::size_t> published{0};  // groups an applier may take
  std::atomic<bool> done{false};                      // `count` is final
  alignas(64) std::size_t count = 0;

  BrickGroups(std::size_t bricks, std::size_t updates) : sources(updates), first(bricks + 1, 0), slots(bricks) {}
  /// How many of groups [0, want) can be taken, waiting while they are being grouped; fewer
  /// only once grouping is done.
  std::size_t available(std::size_t want) const {
    for (unsigned spins = 0;; ++spins) {
      if (published.load(std::memory_order_acquire) >= want) return want;
      if (done.load(std::memory_order_acquire)) return std::min(want, count);
      if (spins < 256) {
        detail::cpuRelax();
        continue;
      }
      std::this_thread::yield();
    }
  }
};

namespace {

// A merge of finalized batches' brick lists (in Morton order): for each brick, in order, calls
// source(update) for every batch holding it, then group(brick). Codes and keys come from the
// batches' lists: reading them through the pointers would miss the cache once per brick, on
// data another thread wrote.
// Bricks the map does not own (MapStore::ownsBrick) are passed over.
template <class Source, class Group>
void mergeBrickLists(const MapStore& store, const std::vector<const UpdateBatch*>& batches, Source&& source,
                     Group&& group) {
  std::vector<std::size_t> pos(batches.size(), 0);
  for (;;) {
    std::size_t from = batches.size();
    for (std::size_t b = 0; b < batches.size(); ++b)
      if (pos[b] < batches[b]->brickCodes().size() &&
          (from == batches.size() || batches[b]->brickCodes()[pos[b]] < batches[from]->brickCodes()[pos[from]]))
        from = b;
    if (from == batches.size()) return;
    const std::uint64_t code = batches[from]->brickCodes()[pos[from]];
    const Key brick = batches[from]->brickKeys()[pos[from]];
    const bool owned = store.ownsBrick(brick);
    for (std::size_t b = 0; b < batches.size(); ++b)
      if (pos[b] < batches[b]->brickCodes().size() && batches[b]->brickCodes()[pos[b]] == code) {
        if (owned) source(batches[b]->bricks()[pos[b]]);
        ++pos[b];
      }
    if (owned) group(brick);
  }
}

}  // namespace

// Fills `groups` in brick order, each group's brick found or made (its slot), publishing the
// groups done every few: appliers take them while the rest are grouped.
void groupByBrick(const MapStore& store, LeafIndex& index, const std::vector<const UpdateBatch*>& batches,
                  BrickGroups& groups) {
  std::uint32_t taken = 0;
  try {
    mergeBrickLists(
        store, batches, [&](const UpdateBatch::BrickUpdates* u) { groups.sources[taken++] = u; },
        [&](const Key& brick) {
          // Slots in brick order, whoever applies the groups: the map does not depend on the threads.
          groups.slots[groups.count] = index.brickSlot(brick);
          groups.first[++groups.count] = taken;
          if (groups.count % BrickGroups::kPublishEvery == 0)
            groups.published.store(groups.count, std::memory_order_release);
        });
  } catch (...) {
    // Appliers finish what was published; the caller rethrows after joining them.
    groups.count = groups.published.load(std::memory_order_relaxed);
    groups.done.store(true, std::memory_order_release);
    throw;
  }
  groups.published.store(groups.count, std::memory_order_release);
  groups.done.store(true, std::memory_order_release);
}

// The union of a group's updates (occupied winning), in `scratch` if there are several.
const UpdateBatch::BrickUpdates* unionOf(const UpdateBatch::BrickUpdates* const* sources, std::size_t n,
                                         UpdateBatch::BrickUpdates& scratch) {
  if (n == 1) return sources[0];
  scratch = *sources[0];
  for (std::size_t s = 1; s < n; ++s)
    for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w) {
      scratch.occupied[w] |= sources[s]->occupied[w];
      scratch.free[w] |= sources[s]->free[w];
    }
  for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w) scratch.free[w] &= ~scratch.occupied[w];
  return &scratch;
}

}  // namespace

void applyBatches(MapStore& store, const std::vector<const UpdateBatch*>& batches, InsertStats& stats, int threads,
                  std::vector<ApplyContext>& contexts) {
  if (threads < 1) throw std::invalid_argument("applyUpdate: threads must be >= 1");
  LeafIndex& index = store.index;
  // Distinct bricks, counted ahead (a cheap pass over the key lists) for the room bricks_ needs:
  // it must not move while appliers hold bricks.
  std::size_t distinct = 0, updates = 0, largest = 0;
  for (const UpdateBatch* b : batches) {
    updates += b->bricks().size();
    largest = std::max(largest, b->bricks().size());
  }
  if (batches.size() == 1 && !store.restricted) {
    distinct = updates;
  } else {
    mergeBrickLists(store, batches, [](const UpdateBatch::BrickUpdates*) {}, [&](const Key&) { ++distinct; });
  }
  BrickGroups groups(distinct, updates);
  index.reserveBricks(distinct);  // room for every brick being new (a first scan)
  // Bricks are independent: threads take runs of them as they go (bricks near the sensor cost
  // far more than distant ones), each with its own scratch, while this thread still groups the
  // batches (serial: brick slots are given in brick order). The results do not depend on who
  // applied which brick: statistics are sums and refreshUpperTree() puts the reshaped bricks in
  // slot order where their order matters.
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(threads), 1 + largest / 64);
  if (contexts.size() < n) contexts.resize(n);
  constexpr std::size_t kGrain = 16;
  alignas(64) std::atomic<std::size_t> next_group{0};  // taken by every applier: a line of its own
  const auto work = [&](std::size_t t) {
    ApplyContext& ctx = contexts[t];
    ctx.reset();
    for (std::size_t g = 0, e = 0;; ++g) {
      if (g == e) {
        g = next_group.fetch_add(kGrain, std::memory_order_relaxed);
        e = groups.available(g + kGrain);
        if (g >= e) break;
      }
      const std::uint32_t* first = &groups.first[g];
      applyBrick(store, *unionOf(&groups.sources[first[0]], first[1] - first[0], ctx.merged), groups.slots[g], ctx);
    }
  };
  parallel::run(n, [&](std::size_t t) {
    if (t == 0) groupByBrick(store, index, batches, groups);  // appliers finish what it published if it throws
    work(t);
  });
  refreshFromContexts(index, contexts, n, stats);
}

void refreshFromContexts(LeafIndex& index, std::vector<ApplyContext>& contexts, std::size_t n, InsertStats& stats) {
  std::vector<std::uint32_t> reshaped;
  for (std::size_t t = 0; t < n; ++t) {
    stats += contexts[t].stats;
    index.addLeafCount(contexts[t].leaf_delta);
    reshaped.insert(reshaped.end(), contexts[t].reshaped.begin(), contexts[t].reshaped.end());
  }
  index.refreshUpperTree(reshaped, static_cast<int>(n), [&] {
    std::vector<const LocalBox*> boxes_of(index.brickCount(), nullptr);
    for (std::size_t c = 0; c < n; ++c)
      for (std::size_t i = 0; i < contexts[c].reshaped.size(); ++i)
        boxes_of[contexts[c].reshaped[i]] = contexts[c].node_boxes.data() + contexts[c].reshaped_boxes[i];
    return boxes_of;
  });
}


void applyGraded(MapStore& store, const std::vector<const GradedScan*>& scans, InsertStats& stats, int threads,
                 std::vector<ApplyContext>& contexts) {
  if (threads < 1) throw std::invalid_argument("applyGraded: threads must be >= 1");
  LeafIndex& index = store.index;
  // The scans' brick lists merged in Morton order: group g is the pairs (scan, brick)
  // parts[first[g] .. first[g + 1]); slots given in brick order (serial): the map does not depend
  // on the threads.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> parts;
  std::vector<std::uint32_t> first{0};
  std::vector<Key> keys;
  {
    std::vector<std::size_t> pos(scans.size(), 0);
    for (;;) {
      std::size_t from = scans.size();
      for (std::size_t s = 0; s < scans.size(); ++s)
        if (pos[s] < scans[s]->brickCount() &&
            (from == scans.size() || scans[s]->brickCode(pos[s]) < scans[from]->brickCode(pos[from])))
          from = s;
      if (from == scans.size()) break;
      const std::uint64_t code = scans[from]->brickCode(pos[from]);
      const Key brick = scans[from]->brick(pos[from]);
      if (!store.ownsBrick(brick)) {  // outside the map's region: passed over
        for (std::size_t s = 0; s < scans.size(); ++s)
          if (pos[s] < scans[s]->brickCount() && scans[s]->brickCode(pos[s]) == code) ++pos[s];
        continue;
      }
      keys.push_back(brick);
      for (std::size_t s = 0; s < scans.size(); ++s)
        if (pos[s] < scans[s]->brickCount() && scans[s]->brickCode(pos[s]) == code)
          parts.emplace_back(static_cast<std::uint32_t>(s), static_cast<std::uint32_t>(pos[s]++));
      first.push_back(static_cast<std::uint32_t>(parts.size()));
    }
  }
  const std::size_t bricks = keys.size();
  index.reserveBricks(bricks);
  std::vector<std::uint32_t> slots(bricks);
  for (std::size_t b = 0; b < bricks; ++b) slots[b] = index.brickSlot(keys[b]);
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(threads), 1 + bricks / 64);
  if (contexts.size() < n) contexts.resize(n);
  constexpr std::size_t kGrain = 16;
  alignas(64) std::atomic<std::size_t> next{0};
  parallel::run(n, [&](std::size_t t) {
    ApplyContext& ctx = contexts[t];
    ctx.reset();
    for (std::size_t g; (g = next.fetch_add(kGrain, std::memory_order_relaxed)) < bricks;)
      for (std::size_t b = g; b < std::min(bricks, g + kGrain); ++b) {
        if (first[b + 1] - first[b] == 1) {
          const auto [s, i] = parts[first[b]];
          applyGradedBrick(store, scans[s]->cells(i), scans[s]->cellCount(i), scans[s]->missMask(i), slots[b], ctx);
          continue;
        }
        // Several scans hold the brick: or their miss masks, merge their cells (by local index)
        // keeping the larger change.
        bool any_miss = false;
        ctx.graded_miss.fill(0);
        ctx.graded_cells.clear();
        for (std::uint32_t p = first[b]; p < first[b + 1]; ++p) {
          const auto [s, i] = parts[p];
          if (const BrickMask* m = scans[s]->missMask(i)) {
            any_miss = true;
            for (std::size_t w = 0; w < ctx.graded_miss.size(); ++w) ctx.graded_miss[w] |= (*m)[w];
          }
          ctx.graded_cells.insert(ctx.graded_cells.end(), scans[s]->cells(i), scans[s]->cells(i) + scans[s]->cellCount(i));
        }
        std::vector<GradedCell>& c = ctx.graded_cells;
        std::sort(c.begin(), c.end(), [](const GradedCell& x, const GradedCell& y) {
          return x.local != y.local ? x.local < y.local : x.delta > y.delta;
        });
        c.erase(std::unique(c.begin(), c.end(), [](const GradedCell& x, const GradedCell& y) { return x.local == y.local; }),
                c.end());
        applyGradedBrick(store, c.data(), c.size(), any_miss ? &ctx.graded_miss : nullptr, slots[b], ctx);
      }
  });
  refreshFromContexts(index, contexts, n, stats);
}

}  // namespace rtog
