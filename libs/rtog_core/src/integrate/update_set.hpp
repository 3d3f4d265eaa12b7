// What an integrator produces and the engine applies (MapEngine::apply, the only mutator of a
// map's leaves besides flush() and clear()). An integrator reads the store (lattice, model) and
// fills buffers of the insertion scratch; the set names those buffers and how they go in.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "integrate/graded_scan.hpp"
#include "integrate/planar/planar_batch.hpp"
#include "integrate/update_batch.hpp"
#include "rtog/core/key.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/stats.hpp"

namespace rtog {

struct MapStore;
struct InsertScratch;
struct AssignedPiece;

struct UpdateSet {
  enum class Kind : std::uint8_t {
    Marks,     ///< finalized update batches: their union, occupied winning (beam, end point)
    Planar,    ///< planar batches of one z-layer, into the planar cache (2D scans)
    Graded,    ///< graded scans: their union, per cell the largest change (range noise, pose blur, fusion)
    Sequence,  ///< graded scans applied one after the other, in order (cone readings)
    StepRuns,  ///< ordered per-beam steps of a grid's rule, into the planar cache (mrpt_grid preset)
    Assigned,  ///< absolute values
  };
  Kind kind = Kind::Marks;
  /// The tracing's counts (beams, skips); apply adds the cells' counts.
  InsertStats stats;
  /// Threads the apply may use (the map does not depend on it).
  int threads = 1;

  std::vector<const UpdateBatch*> batches;  // Marks
  const std::vector<PlanarBatch>* planar = nullptr;  // Planar: batches [0, planar_count) of layer z
  std::size_t planar_count = 0;
  std::vector<const GradedScan*> graded;  // Graded, Sequence
  /// Graded: into the planar cache if every cell lies in one z-layer (InsertParams::planar_cache).
  bool planar_ok = false;
  std::int32_t z = 0;                     // Planar, StepRuns
  const StepRun* runs = nullptr;          // StepRuns
  std::size_t run_count = 0;
  const StepRule* rule = nullptr;
  std::vector<float>* after = nullptr;
  const std::vector<AssignedPiece>* assigned = nullptr;  // Assigned: grouped by brick, disjoint

  /// A set that changes nothing (a scan skipped whole, e.g. over InsertParams::max_scan_cells):
  /// applying it still covers the planar cache, as any set outside it does.
  static UpdateSet nothing(Kind kind, const InsertStats& stats) {
    UpdateSet s;
    s.kind = kind;
    s.stats = stats;
    return s;
  }
  static UpdateSet stepRuns(std::int32_t z, const StepRun* runs, std::size_t n, const StepRule& rule,
                            std::vector<float>* after) {
    UpdateSet s;
    s.kind = Kind::StepRuns;
    s.z = z;
    s.runs = runs;
    s.run_count = n;
    s.rule = &rule;
    s.after = after;
    return s;
  }
};

/// What an integrator works with: the map it reads (never writes) and the buffers it fills.
struct IntegrationContext {
  const MapStore& store;
  InsertScratch& scratch;
};

}  // namespace rtog
