#include "map/map_engine.hpp"

#include <limits>

#include "integrate/batch_apply.hpp"
#include "integrate/planar/step_clip.hpp"

namespace rtog {

InsertStats MapEngine::flush() {
  // Under the lock, so that concurrent readers cover once: the later ones find no layers.
  const std::lock_guard<std::mutex> lock(cover_mutex);
  if (!planar.empty()) store.index.unshareBricks();  // before the appliers write bricks
  const InsertStats stats = planar.cover(store);
  cover_pending.store(false, std::memory_order_release);
  return stats;
}

InsertStats MapEngine::applyClippedStepRuns(const UpdateSet& set) {
  std::vector<StepRun> runs;
  std::vector<std::uint8_t> kept;
  clipStepRuns(store, set.z, set.runs, set.run_count, runs, kept);
  if (runs.empty()) {
    if (set.after) set.after->assign(kept.size(), std::numeric_limits<float>::quiet_NaN());
    return {};
  }
  std::vector<float> applied;
  const InsertStats stats = planar.applyStepRuns(store, set.z, runs.data(), runs.size(), *set.rule, set.after ? &applied : nullptr);
  if (set.after) {
    // Every step of the caller's runs has its entry: the value after it, NaN where the map does not hold the cell.
    set.after->resize(kept.size());
    std::size_t j = 0;
    for (std::size_t i = 0; i < kept.size(); ++i)
      (*set.after)[i] = kept[i] ? applied[j++] : std::numeric_limits<float>::quiet_NaN();
  }
  return stats;
}

void MapEngine::clear() {
  store.clear();
  planar.clear();
  cover_pending.store(false, std::memory_order_release);
}

InsertStats MapEngine::apply(UpdateSet&& set) {
  InsertStats stats = set.stats;
  store.index.unshareBricks();  // a copy's array of bricks cloned once, before appliers on threads
  switch (set.kind) {
    case UpdateSet::Kind::Planar:
      planar.apply(store, *set.planar, set.planar_count, set.z, stats);
      cover_pending.store(true, std::memory_order_release);
      return stats;
    case UpdateSet::Kind::StepRuns:
      if (set.after) set.after->clear();
      if (set.run_count == 0) return {};
      if (store.restricted) {
        stats = applyClippedStepRuns(set);
      } else {
        stats = planar.applyStepRuns(store, set.z, set.runs, set.run_count, *set.rule, set.after);
      }
      cover_pending.store(true, std::memory_order_release);
      return stats;
    case UpdateSet::Kind::Graded: {
      std::int32_t z = 0;
      if (set.planar_ok && gradedLayer(set.graded, z)) {
        planar.applyGradedLayer(store, set.graded, z, stats);
        cover_pending.store(true, std::memory_order_release);
        return stats;
      }
      break;
    }
    default:
      break;
  }
  ensureCovered();
  // The appliers' per-thread contexts: the scratch's (the planar cache needs none).
  const ScratchScope scope(scratch);
  std::vector<ApplyContext>& contexts = (*scope).apply_ctx;
  switch (set.kind) {
    case UpdateSet::Kind::Marks:
      if (!set.batches.empty()) applyBatches(store, set.batches, stats, set.threads, contexts);
      break;
    case UpdateSet::Kind::Graded:
      if (!set.graded.empty()) applyGraded(store, set.graded, stats, set.threads, contexts);
      break;
    case UpdateSet::Kind::Sequence:
      // One measurement after the other, each of its cells once (cone readings).
      for (const GradedScan* g : set.graded) {
        InsertStats applied;
        applyGraded(store, {g}, applied, 1, contexts);
        applied.rays_hit = applied.rays_truncated = 0;
        stats += applied;
      }
      break;
    case UpdateSet::Kind::Assigned:
      if (set.assigned) applyAssigned(store, *set.assigned, stats, contexts);
      break;
    default:
      break;
  }
  return stats;
}

}  // namespace rtog
