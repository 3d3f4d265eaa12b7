// The implementation behind OccupancyMap: the stored map, the planar cache in front of it and
// the insertion scratch, with the rule that readers see the cache covered.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

#include "integrate/planar/planar_cache.hpp"
#include "integrate/scan_integrator.hpp"
#include "integrate/update_batch.hpp"
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
  InsertStats flush();
  void clear();

  InsertStats insertPointCloud(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                               const InsertParams& ip, const std::uint8_t* is_hit);
  InsertStats insertPointSource(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip);
  InsertStats insertBlurred(const WeightedScan* scans, std::size_t n, const InsertParams& ip);
  InsertStats insertCones(const ConeReading* readings, std::size_t n, ConeWeighting w, const InsertParams& ip);
  InsertStats applyStepRuns(std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                            std::vector<float>* after);
  /// Step 1 of an insertion: traces the beams into `batch`; no change to the map.
  void computeUpdate(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                     const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                     InsertStats& stats) const;
  /// Step 2: applies the union of finalized batches (occupied winning across batches too), on
  /// up to `threads` threads; the result does not depend on the count.
  void applyUpdate(const std::vector<const UpdateBatch*>& batches, InsertStats& stats, int threads = 1);

  std::size_t memoryBytes() const { return sizeof(*this) + store.index.memoryBytes() + planar.memoryBytes(); }

  MapStore store;
  PlanarCache planar;
  std::unique_ptr<InsertScratch> scratch;  // while inserting (ScratchScope)
  std::mutex cover_mutex;
  std::atomic<bool> cover_pending{false};

 private:
  /// Runs insert(integrator, flush_pending) with this map's scratch, then notes a pending cover.
  template <class Insert>
  InsertStats integrate(Insert&& insert);
};

}  // namespace rtog
