// Beam insertion: beams -> per-thread update batches -> one set for the engine to apply.
#include "integrate/beam_integrator.hpp"

#include <algorithm>

#include "integrate/beams.hpp"
#include "integrate/insert_scratch.hpp"
#include "integrate/planar/planar_beams.hpp"
#include "integrate/range_noise_integrator.hpp"
#include "parallel/parallel.hpp"
#include "storage/map_store.hpp"

namespace rtog {

// Chunks are taken as threads become free, traced independently; their union does not depend
// on the split. Small chunks (a sixteenth of a thread's share, 256 to 2,048 beams) balance a
// single long-range scan. With discretized end points a thread traces each end cell once, and
// neighbouring beams share end cells across a chunk border: then four large chunks per thread
// (two fixed halves were too uneven, a depth image's rows differing in cost).
std::size_t traceChunk(std::size_t count, std::size_t threads, const InsertParams& ip) {
  return ip.discretize ? std::max<std::size_t>(2048, (count + 4 * threads - 1) / (4 * threads))
                       : std::clamp<std::size_t>(count / (16 * threads), 256, 2048);
}

// Below a few thousand beams a thread costs more than it saves.
std::size_t traceThreads(std::size_t count, const InsertParams& ip) {
  return std::min<std::size_t>(static_cast<std::size_t>(ip.threads), 1 + count / 4096);
}

std::size_t maxScanBricks(const InsertParams& ip) {
  if (ip.max_scan_cells == 0) return 0;
  return static_cast<std::size_t>(std::max<std::uint64_t>(1, ip.max_scan_cells / std::uint64_t(kBrickCells)));
}

namespace {

/// Whether the batches together touch more than `max_bricks` bricks (each batch's bricks are
/// distinct; across batches they may repeat).
bool overBudget(const std::vector<const UpdateBatch*>& batches, std::size_t max_bricks) {
  std::size_t sum = 0;
  for (const UpdateBatch* b : batches) sum += b->brickCodes().size();
  if (max_bricks == 0 || sum <= max_bricks) return false;
  if (batches.size() == 1) return true;
  std::vector<std::uint64_t> all;
  all.reserve(sum);
  for (const UpdateBatch* b : batches) all.insert(all.end(), b->brickCodes().begin(), b->brickCodes().end());
  std::sort(all.begin(), all.end());
  return std::size_t(std::unique(all.begin(), all.end()) - all.begin()) > max_bricks;
}

}  // namespace

UpdateSet integrateScan(const IntegrationContext& ctx, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                        std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  ip.validate();
  if (ip.model == SensorModel::RangeNoise) return RangeNoiseIntegrator(ctx).trace(origin, points, count, ip, is_hit);
  return BeamIntegrator(ctx).trace(origin, points, count, ip, is_hit);
}

UpdateSet integrateScan(const IntegrationContext& ctx, const Eigen::Vector3d& origin, const PointSource& source,
                        const InsertParams& ip) {
  ip.validate();
  if (ip.model == SensorModel::RangeNoise || (ip.planar_cache && mayBePlanar(ctx.store.lattice, origin, source, ip))) {
    // Read whole, then as a scan given whole: the planar test needs every beam.
    std::vector<Eigen::Vector3f> points(source.count);
    points.resize(source.read(0, source.count, points.data()));
    return integrateScan(ctx, origin, points.data(), points.size(), ip, nullptr);
  }
  return BeamIntegrator(ctx).trace(origin, source, ip);
}

UpdateSet BeamIntegrator::trace(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                                const InsertParams& ip, const std::uint8_t* is_hit) {
  Key lo, hi;
  InsertStats stats;
  if (ip.planar_cache &&
      preparePlanarBeams(ctx_.store.lattice, origin, points, count, ip, is_hit, ctx_.scratch.planar_beams, lo, hi, stats))
    return markPlanarBeams(ctx_, origin, count, ip, lo, hi, stats);
  const Lattice& lattice = ctx_.store.lattice;
  return traceChunked(count, ip, [&](UpdateBatch& batch, std::size_t first, std::size_t n, InsertStats& own,
                                     std::size_t max_bricks) {
    return traceBeams(lattice, origin, points + first, n, ip, is_hit ? is_hit + first : nullptr, batch, own, max_bricks);
  });
}

UpdateSet BeamIntegrator::trace(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip) {
  const Lattice& lattice = ctx_.store.lattice;
  return traceChunked(source.count, ip, [&](UpdateBatch& batch, std::size_t first, std::size_t n, InsertStats& own,
                                            std::size_t max_bricks) {
    Eigen::Vector3f piece[kSourcePiece];
    for (std::size_t at = first; at < first + n; at += kSourcePiece) {
      const std::size_t kept = source.read(at, std::min(kSourcePiece, first + n - at), piece);
      if (!traceBeams(lattice, origin, piece, kept, ip, nullptr, batch, own, max_bricks)) return false;
    }
    return true;
  });
}

template <class Trace>
UpdateSet BeamIntegrator::traceChunked(std::size_t count, const InsertParams& ip, Trace&& trace) {
  InsertScratch& scratch = ctx_.scratch;
  const std::size_t threads = traceThreads(count, ip);
  if (scratch.batches.size() < threads) scratch.batches.resize(threads);
  std::vector<InsertStats> part(threads);
  // A thread whose own batch goes over the budget stops them all: the scan's bricks are at least
  // its own, so the scan is skipped whatever the others hold (the same decision for any thread
  // count or timing); else the batches' bricks together decide.
  const std::size_t max_bricks = maxScanBricks(ip);
  const bool traced = parallel::traceChunks(
      count, traceChunk(count, threads, ip), part, [&](std::size_t t) { scratch.batches[t].clear(); },
      [&](std::size_t t, std::size_t first, std::size_t n, InsertStats& own) {
        return trace(scratch.batches[t], first, n, own, max_bricks);
      },
      [&](std::size_t t) { scratch.batches[t].finalize(); });
  UpdateSet set;
  for (std::size_t t = 0; t < threads; ++t) set.batches.push_back(&scratch.batches[t]);
  if (!traced || overBudget(set.batches, max_bricks)) {
    for (std::size_t t = 0; t < threads; ++t) scratch.batches[t].clear();
    InsertStats skipped;
    skipped.skipped_over_budget = count;
    return UpdateSet::nothing(UpdateSet::Kind::Marks, skipped);
  }
  for (std::size_t t = 0; t < threads; ++t) set.stats += part[t];
  set.threads = static_cast<int>(threads);
  return set;
}

bool BeamIntegrator::traceBeams(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit,
                                UpdateBatch& batch, InsertStats& stats, std::size_t max_bricks) {
  const Key origin_key = lattice.key(origin);  // throws for a bad origin
  const Eigen::Vector3d origin_l = lattice.toLattice(origin);
  const BeamRules rules(lattice, ip);
  Eigen::Vector3d end;
  Key end_key;
  for (std::size_t i = 0; i < count; ++i) {
    const BeamEnd kind =
        rules.classify(origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, end, end_key);
    if (!BeamRules::count(kind, stats)) continue;
    rules.mark(kind == BeamEnd::Hit, end_key, batch,
               [&] { batch.queueRayFree(origin_l, rules.walkEnd(end, end_key), origin_key, end_key); });
    if (max_bricks > 0 && batch.brickCount() > max_bricks) return false;
  }
  return true;
}

}  // namespace rtog
