// Insertion: beams -> per-scan update batches (per thread) -> one sweep over the touched bricks.
#include "integrate/scan_integrator.hpp"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <stdexcept>

#include "integrate/batch_apply.hpp"
#include "integrate/beams.hpp"
#include "integrate/planar/fan_skip.hpp"
#include "parallel/parallel.hpp"

namespace rtog {
namespace {

// Idle insertion buffers: as many as maps insert at one time, up to kKeep sets and
// ScratchScope::kIdleBytes in all.
struct ScratchPool {
  static constexpr std::size_t kKeep = 4;
  std::mutex mutex;
  std::vector<std::pair<std::unique_ptr<InsertScratch>, std::size_t>> idle;  // with their bytes
  std::size_t idle_bytes = 0;
  static ScratchPool& instance() {
    static ScratchPool pool;
    return pool;
  }
};

}  // namespace

std::size_t InsertScratch::memoryBytes() const {
  std::size_t bytes = sizeof(*this) + planar_beams.capacity() * sizeof(PlanarBeam);
  for (const GradedScan& g : graded) bytes += sizeof(g) + g.memoryBytes();
  for (const UpdateBatch& b : batches) bytes += sizeof(b) + b.memoryBytes();
  for (const ApplyContext& c : apply_ctx) bytes += c.memoryBytes();
  for (const PlanarBatch& b : planar_batches) bytes += sizeof(b) + b.memoryBytes();
  return bytes;
}

void InsertScratch::shrink() {
  for (UpdateBatch& b : batches) b = UpdateBatch();
  for (ApplyContext& c : apply_ctx) c = ApplyContext();
  for (PlanarBatch& b : planar_batches) b = PlanarBatch();
  std::vector<PlanarBeam>().swap(planar_beams);
  for (GradedScan& g : graded) g = GradedScan();
}

ScratchScope::ScratchScope(std::unique_ptr<InsertScratch>& slot) : slot_(slot), owner_(slot == nullptr) {
  if (!owner_) return;
  ScratchPool& pool = ScratchPool::instance();
  {
    const std::lock_guard<std::mutex> lock(pool.mutex);
    if (!pool.idle.empty()) {
      slot_ = std::move(pool.idle.back().first);
      pool.idle_bytes -= pool.idle.back().second;
      pool.idle.pop_back();
    }
  }
  if (!slot_) slot_ = std::make_unique<InsertScratch>();
}

ScratchScope::~ScratchScope() {
  if (!owner_) return;
  ScratchPool& pool = ScratchPool::instance();
  std::unique_ptr<InsertScratch> scratch = std::move(slot_);
  std::size_t bytes = scratch->memoryBytes();
  const std::lock_guard<std::mutex> lock(pool.mutex);
  if (pool.idle.size() >= ScratchPool::kKeep) return;  // freed here
  if (bytes > keep_at_most_ || pool.idle_bytes + bytes > kIdleBytes) {
    scratch->shrink();
    bytes = scratch->memoryBytes();
  }
  pool.idle_bytes += bytes;
  pool.idle.emplace_back(std::move(scratch), bytes);
}

void releaseInsertBuffers() {
  std::vector<std::pair<std::unique_ptr<InsertScratch>, std::size_t>> idle;
  {
    ScratchPool& pool = ScratchPool::instance();
    const std::lock_guard<std::mutex> lock(pool.mutex);
    idle.swap(pool.idle);
    pool.idle_bytes = 0;
  }
}  // freed here, outside the lock

InsertStats ScanIntegrator::insert(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                                   const InsertParams& ip, const std::uint8_t* is_hit,
                                   const std::function<void()>& flush_pending) {
  ip.validate();
  if (ip.model == SensorModel::RangeNoise) {
    // Graded changes per cell: not the planar cache's two steps.
    flush_pending();
    return insertGraded(origin, points, count, ip, is_hit);
  }
  Key lo, hi;
  InsertStats stats;
  if (ip.planar_cache && preparePlanarBeams(origin, points, count, ip, is_hit, lo, hi, stats))
    return insertPlanar(origin, count, ip, lo, hi, stats);
  flush_pending();
  return traceAndApply(count, ip,
                       [&](UpdateBatch& batch, std::size_t first, std::size_t n, InsertStats& own, std::size_t max_bricks) {
                         return traceBeams(store_.lattice, origin, points + first, n, ip,
                                           is_hit ? is_hit + first : nullptr, batch, own, max_bricks);
                       });
}

InsertStats ScanIntegrator::insert(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip,
                                   const std::function<void()>& flush_pending) {
  ip.validate();
  if (ip.model == SensorModel::RangeNoise || (ip.planar_cache && mayBePlanar(origin, source, ip))) {
    // Read whole, then as a scan given whole: the planar test needs every beam.
    std::vector<Eigen::Vector3f> points(source.count);
    points.resize(source.read(0, source.count, points.data()));
    return insert(origin, points.data(), points.size(), ip, nullptr, flush_pending);
  }
  flush_pending();
  return traceAndApply(source.count, ip,
                       [&](UpdateBatch& batch, std::size_t first, std::size_t n, InsertStats& own, std::size_t max_bricks) {
                         Eigen::Vector3f piece[kSourcePiece];
                         for (std::size_t at = first; at < first + n; at += kSourcePiece) {
                           const std::size_t kept = source.read(at, std::min(kSourcePiece, first + n - at), piece);
                           if (!traceBeams(store_.lattice, origin, piece, kept, ip, nullptr, batch, own, max_bricks))
                             return false;
                         }
                         return true;
                       });
}

bool ScanIntegrator::mayBePlanar(const Eigen::Vector3d& origin, const PointSource& source, const InsertParams& ip) {
  Key origin_key;
  if (!store_.lattice.tryKey(origin, origin_key)) return true;  // the whole scan's path reports it
  // A volumetric scan leaves the origin's z-layer within its first beams.
  Eigen::Vector3f piece[kSourcePiece];
  const std::size_t kept = source.read(0, std::min(kSourcePiece, source.count), piece);
  const BeamRules rules(store_.lattice, ip);
  Eigen::Vector3d end;
  Key end_key;
  for (std::size_t i = 0; i < kept; ++i) {
    const BeamEnd kind = rules.classify(origin, piece[i].cast<double>(), true, end, end_key);
    if ((kind == BeamEnd::Hit || kind == BeamEnd::Truncated) && end_key.z != origin_key.z) return false;
  }
  return true;
}

namespace {

// Chunks are taken as threads become free, traced independently; their union does not depend
// on the split. Small chunks (a sixteenth of a thread's share, 256 to 2,048 beams) balance a
// single long-range scan. With discretized end points a thread traces each end cell once, and
// neighbouring beams share end cells across a chunk border: then four large chunks per thread
// (two fixed halves were too uneven, a depth image's rows differing in cost).
std::size_t chunkSize(std::size_t count, std::size_t threads, const InsertParams& ip) {
  return ip.discretize ? std::max<std::size_t>(2048, (count + 4 * threads - 1) / (4 * threads))
                       : std::clamp<std::size_t>(count / (16 * threads), 256, 2048);
}

// Below a few thousand beams a thread costs more than it saves.
std::size_t threadsFor(std::size_t count, const InsertParams& ip) {
  return std::min<std::size_t>(static_cast<std::size_t>(ip.threads), 1 + count / 4096);
}

/// InsertParams::max_scan_cells in bricks (0: no bound).
std::size_t maxScanBricks(const InsertParams& ip) {
  if (ip.max_scan_cells == 0) return 0;
  return static_cast<std::size_t>(std::max<std::uint64_t>(1, ip.max_scan_cells / std::uint64_t(kBrickCells)));
}

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

InsertStats ScanIntegrator::traceAndApply(std::size_t count, const InsertParams& ip, const TraceChunk& trace) {
  InsertScratch& scratch = scratch_;
  const std::size_t threads = threadsFor(count, ip);
  if (scratch.batches.size() < threads) scratch.batches.resize(threads);
  std::vector<InsertStats> part(threads);
  const std::size_t chunk = chunkSize(count, threads, ip);
  parallel::ChunkClaims claims((count + chunk - 1) / chunk, threads);
  // A thread whose own batch goes over the budget stops them all: the scan's bricks are at least
  // its own, so the scan is skipped whatever the others hold (the same decision for any thread
  // count or timing); else the batches' bricks together decide.
  const std::size_t max_bricks = maxScanBricks(ip);
  std::atomic<bool> over{false};
  parallel::run(threads, [&](std::size_t t) {
    InsertStats own;  // counted locally: neighbouring entries of `part` share a cache line
    UpdateBatch& batch = scratch.batches[t];
    batch.clear();
    for (std::size_t c; (c = claims.next(t)) != parallel::ChunkClaims::kNone;) {
      if (over.load(std::memory_order_relaxed)) break;
      if (!trace(batch, c * chunk, std::min(chunk, count - c * chunk), own, max_bricks)) {
        over.store(true, std::memory_order_relaxed);
        break;
      }
    }
    if (!over.load(std::memory_order_relaxed)) batch.finalize();
    part[t] = own;
  });
  std::vector<const UpdateBatch*> batches;
  for (std::size_t t = 0; t < threads; ++t) batches.push_back(&scratch.batches[t]);
  if (over.load() || overBudget(batches, max_bricks)) {
    for (std::size_t t = 0; t < threads; ++t) scratch.batches[t].clear();
    InsertStats skipped;
    skipped.skipped_over_budget = count;
    return skipped;
  }
  InsertStats stats;
  for (std::size_t t = 0; t < threads; ++t) stats += part[t];
  applyBatches(store_, batches, stats, static_cast<int>(threads), scratch.apply_ctx);
  return stats;
}

InsertStats ScanIntegrator::insertPlanar(const Eigen::Vector3d& origin, std::size_t count, const InsertParams& ip,
                                         const Key& lo, const Key& hi, InsertStats stats) {
  InsertScratch& scratch = scratch_;
  const std::size_t threads = threadsFor(count, ip);
  if (scratch.planar_batches.size() < threads) scratch.planar_batches.resize(threads);
  std::vector<InsertStats> part(threads);
  const std::size_t chunk = chunkSize(count, threads, ip);
  parallel::ChunkClaims claims((count + chunk - 1) / chunk, threads);
  const Key origin_key = store_.lattice.key(origin);
  const BeamRules rules(store_.lattice, ip);
  parallel::run(threads, [&](std::size_t t) {
    InsertStats own;
    PlanarBatch& batch = scratch.planar_batches[t];
    batch.reset(lo, hi);
    for (std::size_t c; (c = claims.next(t)) != parallel::ChunkClaims::kNone;) {
      const std::size_t first = c * chunk, n = std::min(chunk, count - first);
      for (std::size_t i = first; i < first + n; ++i) {
        const PlanarBeam& beam = scratch.planar_beams[i];
        if (!beam.traced) continue;
        rules.mark(beam.hit, beam.end, batch, [&] { batch.markRayFree(beam.seg, origin_key, beam.skip_runs); });
      }
    }
    batch.finalize();
    part[t] = own;
  });
  for (std::size_t t = 0; t < threads; ++t) stats += part[t];
  planar_.apply(store_, scratch.planar_batches, threads, lo.z, stats);
  return stats;
}

InsertStats ScanIntegrator::insertGraded(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                         std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  (void)store_.lattice.key(origin);  // throws for a bad origin, before any thread starts
  InsertScratch& scratch = scratch_;
  const std::size_t threads = threadsFor(count, ip);
  if (scratch.graded.size() < threads) scratch.graded.resize(threads);
  std::vector<InsertStats> part(threads);
  // Chunks taken as threads become free; the union of the threads' scans does not depend on the
  // split (per cell the largest change, miss masks or-ed).
  const std::size_t chunk = std::clamp<std::size_t>(count / (16 * threads), 256, 2048);
  parallel::ChunkClaims claims((count + chunk - 1) / chunk, threads);
  parallel::run(threads, [&](std::size_t t) {
    InsertStats own;
    GradedScan& scan = scratch.graded[t];
    scan.clear();
    for (std::size_t c; (c = claims.next(t)) != parallel::ChunkClaims::kNone;) {
      const std::size_t first = c * chunk, n = std::min(chunk, count - first);
      scan.traceRangeNoise(store_.lattice, store_.model, origin, points + first, n, ip, is_hit ? is_hit + first : nullptr,
                           own);
    }
    scan.finalize();
    part[t] = own;
  });
  InsertStats stats;
  for (std::size_t t = 0; t < threads; ++t) stats += part[t];
  std::vector<const GradedScan*> scans;
  for (std::size_t t = 0; t < threads; ++t) scans.push_back(&scratch.graded[t]);
  applyGraded(store_, scans, stats, static_cast<int>(threads), scratch.apply_ctx);
  return stats;
}

bool ScanIntegrator::preparePlanarBeams(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                        std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit, Key& lo,
                                        Key& hi, InsertStats& stats) {
  const Lattice& lattice = store_.lattice;
  // A planar batch of more than this many bricks (16 MiB: a scan 400 m wide at 5 cm) takes
  // the general path instead.
  constexpr std::size_t kMaxPlanarTiles = std::size_t{1} << 18;
  Key origin_key;
  if (!lattice.tryKey(origin, origin_key)) return false;
  const Eigen::Vector3d origin_l = lattice.toLattice(origin);
  lo = hi = origin_key;
  // Grown beam by beam: a volumetric scan usually leaves the layer within its first beams, and
  // sizing for all of them (a depth image: 307,200) cost more than its whole planar test.
  std::vector<PlanarBeam>& beams = scratch_.planar_beams;
  beams.clear();
  InsertStats counts;  // into `stats` only if the scan is planar: else the general path counts
  const BeamRules rules(lattice, ip);
  Eigen::Vector3d end;
  for (std::size_t i = 0; i < count; ++i) {
    PlanarBeam& beam = beams.emplace_back();
    const BeamEnd kind =
        rules.classify(origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, end, beam.end);
    beam.traced = false;
    beam.skip_runs = 0;
    if (kind != BeamEnd::Hit && kind != BeamEnd::Truncated) {
      BeamRules::count(kind, counts);
      continue;
    }
    if (beam.end.z != origin_key.z) return false;
    lo = Key{std::min(lo.x, beam.end.x), std::min(lo.y, beam.end.y), lo.z};
    hi = Key{std::max(hi.x, beam.end.x), std::max(hi.y, beam.end.y), hi.z};
    beam.traced = true;
    beam.hit = kind == BeamEnd::Hit;
    BeamRules::count(kind, counts);
    beam.seg = planarSegment(origin_l, rules.walkEnd(end, beam.end), origin_key, beam.end);
  }
  if (PlanarBatch::tilesFor(lo, hi) > kMaxPlanarTiles) return false;
  // A budget smaller than the batch's box: the general path counts the bricks touched.
  const std::uint64_t box_cells = std::uint64_t(PlanarBatch::tilesFor(lo, hi)) * kBrickSize * kBrickSize;
  if (ip.max_scan_cells > 0 && box_cells > ip.max_scan_cells) return false;
  // Discretized beams are traced once per end cell, which a skip could not rely on.
  if (rules.tracesFree() && !rules.discretize()) fanSkipRuns(beams.data(), count);
  stats += counts;
  return true;
}

bool ScanIntegrator::traceBeams(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
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
