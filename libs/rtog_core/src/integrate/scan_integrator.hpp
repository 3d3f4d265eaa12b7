// The scan integrator: one scan's beams traced into update batches (in parallel), then applied
// to the map, through the planar cache when the scan lies in one z-layer.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "integrate/brick_update.hpp"
#include "integrate/graded_scan.hpp"
#include "integrate/planar/planar_batch.hpp"
#include "integrate/planar/planar_cache.hpp"
#include "integrate/update_batch.hpp"
#include "rtog/core/cone.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/point_source.hpp"
#include "rtog/core/pose_blur.hpp"
#include "rtog/core/stats.hpp"
#include "storage/map_store.hpp"

namespace rtog {

/// Buffers of one insertion: per-thread update batches and apply contexts, a planar scan's
/// beams and batches. A map holds them only while it inserts: they come from a process-wide
/// pool and go back to it, so maps do not each keep buffers the size of their largest scan
/// (a particle filter keeps a map per particle; one VLP-16 scan's batch is 20 MB), and a new
/// map starts with buffers already faulted in.
struct InsertScratch {
  std::vector<UpdateBatch> batches;  // per thread
  std::vector<ApplyContext> apply_ctx;
  std::vector<PlanarBatch> planar_batches;  // per thread
  std::vector<PlanarBeam> planar_beams;
  std::vector<GradedScan> graded;  // RangeNoise scans, per thread

  std::size_t memoryBytes() const;
  /// Frees the buffers that grow with a scan, keeping the per-thread objects.
  void shrink();
};

/// Holds `slot` filled for its lifetime, from the pool unless an enclosing scope holds it. A set
/// goes back to the pool whole only if it fits under kIdleBytes with the other idle sets and
/// under keepAtMost(); else it is shrunk first. So the heap a process holds between insertions
/// stays near its maps' own bytes (one VLP-16 scan's batches are about 20 MB, more than the map
/// of that scan at 10 cm), while scans that fit keep their buffers faulted in for the next one.
class ScratchScope {
 public:
  static constexpr std::size_t kIdleBytes = std::size_t{8} << 20;
  explicit ScratchScope(std::unique_ptr<InsertScratch>& slot);
  ~ScratchScope();
  ScratchScope(const ScratchScope&) = delete;
  ScratchScope& operator=(const ScratchScope&) = delete;
  InsertScratch& operator*() const { return *slot_; }
  /// The most bytes this set may keep in the pool (the map's own bytes allow for it).
  void keepAtMost(std::size_t bytes) { keep_at_most_ = bytes; }

 private:
  std::unique_ptr<InsertScratch>& slot_;
  bool owner_;
  std::size_t keep_at_most_ = kIdleBytes;
};

/// Frees the pool's idle buffers (up to four are kept: one per map inserting at a time).
void releaseInsertBuffers();

class ScanIntegrator {
 public:
  ScanIntegrator(MapStore& store, PlanarCache& planar, InsertScratch& scratch)
      : store_(store), planar_(planar), scratch_(scratch) {}

  /// Integrates one scan (OccupancyMap::insertPointCloud). flush_pending() is called first
  /// if the scan does not go through the planar cache.
  InsertStats insert(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                     const InsertParams& ip, const std::uint8_t* is_hit, const std::function<void()>& flush_pending);

  /// Integrates one scan read piece by piece (OccupancyMap::insertPointSource):
  /// as above, but no copy of the scan is made unless it may be planar or is graded.
  InsertStats insert(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip,
                     const std::function<void()>& flush_pending);

  /// Integrates one scan from a weighted set of poses (OccupancyMap::insertBlurred; pose_blur.cpp).
  InsertStats insertBlurred(const WeightedScan* scans, std::size_t n, const InsertParams& ip,
                            const std::function<void()>& flush_pending);

  /// Integrates readings of range sensors with a wide beam, one update each, in order
  /// (OccupancyMap::insertCones; cone.cpp).
  InsertStats insertCones(const ConeReading* readings, std::size_t n, ConeWeighting w, const InsertParams& ip,
                          const std::function<void()>& flush_pending);

  /// Traces beams into `batch` (no change to the map). Throws std::out_of_range if the origin
  /// has no key. With max_bricks > 0, stops and returns false once the batch holds more bricks.
  static bool traceBeams(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                         std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                         InsertStats& stats, std::size_t max_bricks = 0);

 private:
  /// Points read from a PointSource at a time (24 KiB, on the tracing thread's stack).
  static constexpr std::size_t kSourcePiece = 2048;
  /// false: the batch went over `max_bricks` (InsertParams::max_scan_cells), tracing stopped.
  using TraceChunk = std::function<bool(UpdateBatch& batch, std::size_t first, std::size_t n, InsertStats& stats,
                                        std::size_t max_bricks)>;
  /// Traces beams [0, count) in chunks on the insertion threads, each chunk by
  /// trace(thread's batch, first, n, thread's stats, max_bricks), then applies the batches; a
  /// scan whose batches touch more bricks than ip.max_scan_cells allows is skipped whole.
  InsertStats traceAndApply(std::size_t count, const InsertParams& ip, const TraceChunk& trace);
  /// A planar scan whose beams preparePlanarBeams() set out: marked, then kept in the planar cache.
  InsertStats insertPlanar(const Eigen::Vector3d& origin, std::size_t count, const InsertParams& ip, const Key& lo,
                           const Key& hi, InsertStats stats);
  /// False if the source's first beams leave the origin's z-layer (then no planar batch takes it).
  bool mayBePlanar(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip);
  /// A RangeNoise scan: traced into per-thread graded scans, then applied.
  InsertStats insertGraded(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                           const InsertParams& ip, const std::uint8_t* is_hit);
  /// True if every traced beam of the scan stays in the origin's z-layer and the scan is not too
  /// wide for a planar batch: then the beams in exact planar form, with the runs each can skip
  /// (fanSkipRuns), are in scratch_.planar_beams, [lo, hi] bounds their cells in x and y, and
  /// `stats` counts them.
  bool preparePlanarBeams(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                          const InsertParams& ip, const std::uint8_t* is_hit, Key& lo, Key& hi, InsertStats& stats);

  MapStore& store_;
  PlanarCache& planar_;
  InsertScratch& scratch_;
};

}  // namespace rtog
