// The buffers of one insertion, lent by a process-wide pool to the map that inserts.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "integrate/brick_update.hpp"
#include "integrate/graded_scan.hpp"
#include "integrate/planar/planar_batch.hpp"
#include "integrate/update_batch.hpp"

namespace rtog {

/// A cell value of a CellAssignment, in its brick (UpdateSet::Kind::Assigned).
struct AssignedPiece {
  Key brick;
  LeafEntry leaf;
};

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
  std::vector<GradedScan> graded;  // RangeNoise scans per thread; pose blur, cones, fusion
  SharedEnds shared_ends;  // RangeNoise: the end cells whose beams share a band
  std::vector<AssignedPiece> assigned;  // grouped by brick
  std::vector<std::vector<Eigen::Vector3f>> moved_points;  // pose blur: the scan moved to each pose

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

}  // namespace rtog
