// The implementation behind OccupancyMap: the stored map, the planar cache in front of it and
// the insertion scratch, with the rule that readers see the cache covered. Evidence enters by
// one door: an integrator produces an UpdateSet (integrate/update_set.hpp), apply() applies it.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>

#include "integrate/insert_scratch.hpp"
#include "integrate/planar/planar_cache.hpp"
#include "integrate/update_set.hpp"
#include "storage/map_store.hpp"

namespace rtog {

class MapEngine {
 public:
  explicit MapEngine(const MapParams& params) : store(params) {}
  /// A copy of a covered store (the source's cache is not copied; scratch never is).
  explicit MapEngine(const MapStore& covered) : store(covered) {}

  /// Covers pending planar layers once, under a lock: concurrent readers of a map may call it.
  void ensureCovered() {
    if (cover_pending.load(std::memory_order_acquire)) flush();
  }
  /// For readers that read the planar cache as it is (OccupancyMap::write): the lock covers
  /// take, held after covering unless every cached layer is a lone coded one, which
  /// PlanarCache::coveredLeaves reads without covering.
  std::unique_lock<std::mutex> lockReadableCache() {
    std::unique_lock<std::mutex> lock(cover_mutex);
    if (cover_pending.load(std::memory_order_acquire) && !planar.lonesInCodes()) {
      lock.unlock();
      flush();
      lock.lock();
    }
    return lock;
  }
  // The only mutators of the store: flush(), clear() and apply().
  InsertStats flush();
  void clear();
  /// Applies an integrator's set: planar batches and step runs into the planar cache (a cover
  /// pending after), every other kind after covering the cache. The set's buffers are those of
  /// this map's scratch (held by the caller's ScratchScope, or by apply's own).
  InsertStats apply(UpdateSet&& set);
  /// A map restricted to a region: the set's step runs clipped to its bricks (step_clip.hpp).
  InsertStats applyClippedStepRuns(const UpdateSet& set);

  /// Runs produce(IntegrationContext) -> UpdateSet with this map's scratch, then apply().
  template <class Produce>
  InsertStats integrate(Produce&& produce) {
    ScratchScope scope(scratch);
    InsertStats stats = apply(produce(IntegrationContext{store, *scope}));
    // Buffers kept for the next scan may add half the map's own bytes to what the process holds.
    scope.keepAtMost(store.index.memoryBytesAtLeast() / 2 + planar.memoryBytes());
    return stats;
  }

  std::size_t memoryBytes() const { return sizeof(*this) + store.index.memoryBytes() + planar.memoryBytes(); }

  MapStore store;
  PlanarCache planar;
  std::unique_ptr<InsertScratch> scratch;  // while inserting (ScratchScope)
  std::mutex cover_mutex;
  std::atomic<bool> cover_pending{false};
};

}  // namespace rtog
