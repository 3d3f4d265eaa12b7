// The beam and end-point sensor models: a scan's beams traced into update batches on the
// insertion threads (UpdateSet::Kind::Marks), or, when every beam stays in the origin's z-layer,
// into planar batches for the planar cache (Kind::Planar; planar/planar_beams.hpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "integrate/update_set.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/point_source.hpp"

namespace rtog {

class Lattice;

/// Points read from a PointSource at a time (24 KiB, on the reading thread's stack).
constexpr std::size_t kSourcePiece = 2048;

class BeamIntegrator {
 public:
  explicit BeamIntegrator(const IntegrationContext& ctx) : ctx_(ctx) {}

  /// One scan given whole (OccupancyMap::insertPointCloud).
  UpdateSet trace(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                  const InsertParams& ip, const std::uint8_t* is_hit);
  /// One scan read piece by piece (OccupancyMap::insertPointSource): no copy of the scan unless
  /// it may be planar.
  UpdateSet trace(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip);

  /// Traces beams into `batch`. Throws std::out_of_range if the origin has no key. With
  /// max_bricks > 0, stops and returns false once the batch holds more bricks.
  static bool traceBeams(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                         std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                         InsertStats& stats, std::size_t max_bricks = 0);

 private:
  /// Traces beams [0, count) in chunks on the insertion threads, each chunk by
  /// trace(thread's batch, first, n, thread's stats, max_bricks); a scan whose batches touch more
  /// bricks than ip.max_scan_cells allows is skipped whole.
  template <class Trace>
  UpdateSet traceChunked(std::size_t count, const InsertParams& ip, Trace&& trace);

  IntegrationContext ctx_;
};

/// A scan's integrator by its sensor model: RangeNoise graded (RangeNoiseIntegrator), the others
/// by beams (BeamIntegrator).
UpdateSet integrateScan(const IntegrationContext& ctx, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                        std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit);
UpdateSet integrateScan(const IntegrationContext& ctx, const Eigen::Vector3d& origin, const PointSource& source,
                        const InsertParams& ip);

/// Threads and chunks of a scan's tracing (shared by the scan integrators).
std::size_t traceThreads(std::size_t count, const InsertParams& ip);
std::size_t traceChunk(std::size_t count, std::size_t threads, const InsertParams& ip);
/// InsertParams::max_scan_cells in bricks (0: no bound).
std::size_t maxScanBricks(const InsertParams& ip);

}  // namespace rtog
