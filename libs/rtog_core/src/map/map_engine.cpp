#include "map/map_engine.hpp"

#include "integrate/batch_apply.hpp"

namespace rtog {

InsertStats MapEngine::flush() {
  // Under the lock, so that concurrent readers cover once: the later ones find no layers.
  const std::lock_guard<std::mutex> lock(cover_mutex);
  const InsertStats stats = planar.cover(store);
  cover_pending.store(false, std::memory_order_release);
  return stats;
}

void MapEngine::clear() {
  store.clear();
  planar.clear();
  cover_pending.store(false, std::memory_order_release);
}

template <class Insert>
InsertStats MapEngine::integrate(Insert&& insert) {
  ScratchScope scope(scratch);
  ScanIntegrator integrator(store, planar, *scope);
  const InsertStats stats = insert(integrator, [this] {
    if (cover_pending.load(std::memory_order_acquire)) flush();
  });
  if (!planar.empty()) cover_pending.store(true, std::memory_order_release);
  // Buffers kept for the next scan may add half the map's own bytes to what the process holds.
  scope.keepAtMost(store.index.memoryBytesAtLeast() / 2 + planar.memoryBytes());
  return stats;
}

InsertStats MapEngine::insertPointCloud(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                        std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  return integrate([&](ScanIntegrator& in, const std::function<void()>& flush_pending) {
    return in.insert(origin, points, count, ip, is_hit, flush_pending);
  });
}

InsertStats MapEngine::insertPointSource(const Eigen::Vector3d& origin, const PointSource& source,
                                        const InsertParams& ip) {
  return integrate([&](ScanIntegrator& in, const std::function<void()>& flush_pending) {
    return in.insert(origin, source, ip, flush_pending);
  });
}

InsertStats MapEngine::insertBlurred(const WeightedScan* scans, std::size_t n, const InsertParams& ip) {
  return integrate([&](ScanIntegrator& in, const std::function<void()>& flush_pending) {
    return in.insertBlurred(scans, n, ip, flush_pending);
  });
}

InsertStats MapEngine::insertCones(const ConeReading* readings, std::size_t n, ConeWeighting w,
                                   const InsertParams& ip) {
  ScratchScope scope(scratch);
  const InsertStats stats = ScanIntegrator(store, planar, *scope).insertCones(readings, n, w, ip, [this] {
    if (cover_pending.load(std::memory_order_acquire)) flush();
  });
  scope.keepAtMost(store.index.memoryBytesAtLeast() / 2 + planar.memoryBytes());
  return stats;
}

InsertStats MapEngine::applyStepRuns(std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                                     std::vector<float>* after) {
  if (after) after->clear();
  if (n == 0) return {};
  const InsertStats stats = planar.applyStepRuns(store, z, runs, n, rule, after);
  cover_pending.store(true, std::memory_order_release);
  return stats;
}

void MapEngine::computeUpdate(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                              const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                              InsertStats& stats) const {
  ScanIntegrator::traceBeams(store.lattice, origin, points, count, ip, is_hit, batch, stats);
}

void MapEngine::applyUpdate(const std::vector<const UpdateBatch*>& batches, InsertStats& stats, int threads) {
  const ScratchScope scope(scratch);
  ensureCovered();
  applyBatches(store, batches, stats, threads, (*scope).apply_ctx);
}

}  // namespace rtog
