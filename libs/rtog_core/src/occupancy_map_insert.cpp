// Insertion: beams -> per-scan update batch -> one sweep over the touched bricks.
#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <array>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define RTOG_AVX2_DISPATCH 1
#endif

#include "rtog/core/detail/cover.hpp"
#include "rtog/core/detail/layer_update.hpp"
#include "rtog/core/detail/radix_sort.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/ray_traversal.hpp"

namespace rtog {

using detail::BrickMask;
using detail::coverGreedily;
using detail::coverLayer;
using detail::localIdx;
using detail::xRun;

namespace {

// Updates the 64 cells of a layer word, `occupied` ones by `hit` and `free` ones by `miss`
// (disjoint masks), clamped to [lo, hi]; returns the mask of updated cells whose value stayed.
// Touched words are mostly dense (60 % of the cells of a word on the SENA scans), so every
// cell is computed and the untouched ones are kept by a select: four cells per SSE2 step.
std::uint64_t updateLayerWord(float* values, std::uint64_t occupied, std::uint64_t free, float hit, float miss,
                              float lo, float hi) {
#if defined(__SSE2__)
  alignas(16) static constexpr std::uint32_t kLanes[16][4] = {
      {0, 0, 0, 0}, {~0u, 0, 0, 0}, {0, ~0u, 0, 0}, {~0u, ~0u, 0, 0},
      {0, 0, ~0u, 0}, {~0u, 0, ~0u, 0}, {0, ~0u, ~0u, 0}, {~0u, ~0u, ~0u, 0},
      {0, 0, 0, ~0u}, {~0u, 0, 0, ~0u}, {0, ~0u, 0, ~0u}, {~0u, ~0u, 0, ~0u},
      {0, 0, ~0u, ~0u}, {~0u, 0, ~0u, ~0u}, {0, ~0u, ~0u, ~0u}, {~0u, ~0u, ~0u, ~0u}};
  const auto lanes = [](std::uint64_t bits, int g) {
    return _mm_load_ps(reinterpret_cast<const float*>(kLanes[(bits >> (4 * g)) & 15u]));
  };
  const __m128 vhit = _mm_set1_ps(hit), vmiss = _mm_set1_ps(miss), vlo = _mm_set1_ps(lo), vhi = _mm_set1_ps(hi);
  std::uint64_t same = 0;
#pragma GCC unroll 16
  for (int g = 0; g < 16; ++g) {
    const __m128 o = lanes(occupied, g), f = lanes(free, g), touched = _mm_or_ps(o, f);
    const __m128 delta = _mm_or_ps(_mm_and_ps(o, vhit), _mm_and_ps(f, vmiss));
    const __m128 v = _mm_loadu_ps(values + 4 * g);
    const __m128 nv = _mm_min_ps(_mm_max_ps(_mm_add_ps(v, delta), vlo), vhi);
    _mm_storeu_ps(values + 4 * g, _mm_or_ps(_mm_and_ps(touched, nv), _mm_andnot_ps(touched, v)));
    same |= static_cast<std::uint64_t>(_mm_movemask_ps(_mm_cmpeq_ps(nv, v))) << (4 * g);
  }
  return same & (occupied | free);
#else
  std::uint64_t same = 0;
  const auto update = [&](std::uint64_t bits, float delta) {
    for (; bits; bits &= bits - 1) {
      const int b = __builtin_ctzll(bits);
      const float v = values[b], nv = std::min(std::max(v + delta, lo), hi);
      same |= static_cast<std::uint64_t>(nv == v) << b;
      values[b] = nv;
    }
  };
  update(free, miss);
  update(occupied, hit);
  return same;
#endif
}

enum class BeamEnd { Hit, Truncated, NonFinite, ZeroLength, OutOfRange, TooLong };

// Where a beam from `origin` to `p` ends (cut at max_range) and its end cell.
inline BeamEnd endOfBeam(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3d& p,
                         bool returned, const InsertParams& ip, Eigen::Vector3d& end, Key& end_key) {
  const double max_range = ip.max_range;
  if (!p.allFinite()) return BeamEnd::NonFinite;
  const Eigen::Vector3d diff = p - origin;
  const double dist2 = diff.squaredNorm();
  if (!(dist2 > 0.0)) return BeamEnd::ZeroLength;
  end = p;
  if (max_range > 0.0 && std::isfinite(max_range) && dist2 > max_range * max_range) {
    const double dist = std::sqrt(dist2);
    if (dist > max_range) {
      end = origin + diff * (max_range / dist);
      returned = false;
    }
  }
  if (!lattice.tryKey(end, end_key)) return BeamEnd::OutOfRange;
  if (ip.max_ray_cells > 0) {
    const double longest = ip.max_ray_cells * lattice.resolution();
    if ((end - origin).squaredNorm() > longest * longest) return BeamEnd::TooLong;
  }
  return returned ? BeamEnd::Hit : BeamEnd::Truncated;
}

#if defined(RTOG_AVX2_DISPATCH)
// updateLayerWord eight cells a step, for CPUs that have AVX2 (chosen at run time: the default
// build targets any x86-64). The same operations per cell, so the same values.
__attribute__((target("avx2"))) std::uint64_t updateLayerWordAvx2(float* values, std::uint64_t occupied,
                                                                  std::uint64_t free, float hit, float miss, float lo,
                                                                  float hi) {
  // (A lambda would not inherit the target.)
  const __m256i lane_bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256 vhit = _mm256_set1_ps(hit), vmiss = _mm256_set1_ps(miss), vlo = _mm256_set1_ps(lo),
               vhi = _mm256_set1_ps(hi);
  std::uint64_t same = 0;
#pragma GCC unroll 8
  for (int g = 0; g < 8; ++g) {
    const __m256i ob = _mm256_set1_epi32(static_cast<int>((occupied >> (8 * g)) & 255u));
    const __m256i fb = _mm256_set1_epi32(static_cast<int>((free >> (8 * g)) & 255u));
    const __m256 o = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(ob, lane_bit), lane_bit));
    const __m256 f = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(fb, lane_bit), lane_bit));
    const __m256 touched = _mm256_or_ps(o, f);
    const __m256 delta = _mm256_or_ps(_mm256_and_ps(o, vhit), _mm256_and_ps(f, vmiss));
    const __m256 v = _mm256_loadu_ps(values + 8 * g);
    const __m256 nv = _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(v, delta), vlo), vhi);
    _mm256_storeu_ps(values + 8 * g, _mm256_blendv_ps(v, nv, touched));
    same |= static_cast<std::uint64_t>(_mm256_movemask_ps(_mm256_cmp_ps(nv, v, _CMP_EQ_OQ))) << (8 * g);
  }
  return same & (occupied | free);
}

// Counted with the POPCNT instruction, which every AVX2 CPU has.
__attribute__((target("avx2,popcnt"))) void updateLayerAvx2(float* values, std::uint64_t* known,
                                                             const std::uint64_t* occupied, const std::uint64_t* free,
                                                             const float deltas[4], detail::LayerCounts& counts) {
  for (std::size_t w = 0; w < kLayerWords; ++w) {
    const std::uint64_t o = occupied[w], f = free[w] & ~o;
    if ((o | f) == 0) continue;
    const std::uint64_t same = updateLayerWordAvx2(values + w * 64, o, f, deltas[0], deltas[1], deltas[2], deltas[3]);
    counts.unchanged += static_cast<std::size_t>(__builtin_popcountll(same & known[w]));
    counts.free += static_cast<std::size_t>(__builtin_popcountll(f));
    counts.occupied += static_cast<std::size_t>(__builtin_popcountll(o));
    known[w] |= o | f;
  }
}
#endif

void updateLayer(float* values, std::uint64_t* known, const std::uint64_t* occupied, const std::uint64_t* free,
                 const float deltas[4], detail::LayerCounts& counts) {
  for (std::size_t w = 0; w < kLayerWords; ++w) {
    const std::uint64_t o = occupied[w], f = free[w] & ~o;
    if ((o | f) == 0) continue;
    const std::uint64_t same = updateLayerWord(values + w * 64, o, f, deltas[0], deltas[1], deltas[2], deltas[3]);
    counts.unchanged += popcount64(same & known[w]);
    counts.free += popcount64(f);
    counts.occupied += popcount64(o);
    known[w] |= o | f;
  }
}

// Chunks of a scan's beams for threads to claim. A pair of threads shares a range of chunks,
// one taking chunks from its front and the other from its back: each traces neighbouring beams,
// which touch the same bricks (a scan's beams come in sweep order), so the two batches share
// few bricks, and they meet wherever their work balances. A thread whose range is used up
// helps with the others' from their front (or back).
class ChunkClaims {
 public:
  static constexpr std::size_t kNone = ~std::size_t{0};
  ChunkClaims(std::size_t chunks, std::size_t threads) : ranges_((threads + 1) / 2) {
    for (std::size_t r = 0; r < ranges_.size(); ++r)
      ranges_[r].ends.store(pack(chunks * r / ranges_.size(), chunks * (r + 1) / ranges_.size()),
                            std::memory_order_relaxed);
  }
  std::size_t next(std::size_t thread) {
    const bool from_back = thread % 2 == 1;
    for (std::size_t k = 0; k < ranges_.size(); ++k) {
      std::atomic<std::uint64_t>& ends = ranges_[(thread / 2 + k) % ranges_.size()].ends;
      std::uint64_t v = ends.load(std::memory_order_relaxed);
      for (;;) {
        const std::uint64_t front = v >> 32, back = v & 0xFFFFFFFFu;
        if (front >= back) break;
        const std::uint64_t claimed = from_back ? pack(front, back - 1) : pack(front + 1, back);
        if (ends.compare_exchange_weak(v, claimed, std::memory_order_relaxed))
          return static_cast<std::size_t>(from_back ? back - 1 : front);
      }
    }
    return kNone;
  }

 private:
  // Chunk indices in 32 bits: a chunk is at least 256 beams.
  static std::uint64_t pack(std::size_t front, std::size_t back) {
    return (static_cast<std::uint64_t>(front) << 32) | static_cast<std::uint64_t>(back);
  }
  struct alignas(64) Range {
    std::atomic<std::uint64_t> ends;  // [front, back) in the high and low 32 bits
  };
  std::vector<Range> ranges_;
};

}  // namespace

namespace detail {

std::array<UpdateLayerFn, 2> layerUpdateKernels() {
#if defined(RTOG_AVX2_DISPATCH)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt")) return {updateLayer, updateLayerAvx2};
#endif
  return {updateLayer, nullptr};
}

}  // namespace detail

// Idle insertion buffers: as many as maps insert at one time, up to kKeep.
struct OccupancyMap::ScratchPool {
  static constexpr std::size_t kKeep = 4;
  std::mutex mutex;
  std::vector<std::unique_ptr<InsertScratch>> idle;
  static ScratchPool& instance() {
    static ScratchPool pool;
    return pool;
  }
};

OccupancyMap::ScratchScope::ScratchScope(OccupancyMap& map) : map_(map), owner_(map.scratch_ == nullptr) {
  if (!owner_) return;
  ScratchPool& pool = ScratchPool::instance();
  {
    const std::lock_guard<std::mutex> lock(pool.mutex);
    if (!pool.idle.empty()) {
      map_.scratch_ = std::move(pool.idle.back());
      pool.idle.pop_back();
    }
  }
  if (!map_.scratch_) map_.scratch_ = std::make_unique<InsertScratch>();
}

OccupancyMap::ScratchScope::~ScratchScope() {
  if (!owner_) return;
  ScratchPool& pool = ScratchPool::instance();
  const std::lock_guard<std::mutex> lock(pool.mutex);
  if (pool.idle.size() < ScratchPool::kKeep) pool.idle.push_back(std::move(map_.scratch_));
  map_.scratch_.reset();
}

void OccupancyMap::releaseInsertBuffers() {
  std::vector<std::unique_ptr<InsertScratch>> idle;
  {
    ScratchPool& pool = ScratchPool::instance();
    const std::lock_guard<std::mutex> lock(pool.mutex);
    idle.swap(pool.idle);
  }
}  // freed here, outside the lock

InsertStats OccupancyMap::insertPointCloud(const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                                           std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit) {
  if (ip.threads < 1) throw std::invalid_argument("InsertParams: threads must be >= 1");
  const ScratchScope scope(*this);
  InsertScratch& scratch = *scratch_;
  Key lo, hi;
  InsertStats stats;
  const bool planar = ip.planar_cache && preparePlanarBeams(origin, points, count, ip, is_hit, lo, hi, stats);
  if (!planar && hasPendingCover()) flush();
  // Below a few thousand beams a thread costs more than it saves.
  const std::size_t threads = std::min<std::size_t>(static_cast<std::size_t>(ip.threads), 1 + count / 4096);
  if (scratch.batches.size() < threads) scratch.batches.resize(threads);
  if (planar && scratch.planar_batches.size() < threads) scratch.planar_batches.resize(threads);
  std::vector<InsertStats> part(threads);
  std::vector<std::exception_ptr> errors(threads);
  // Chunks taken as threads become free, traced independently; their union does not depend on
  // the split. Small chunks (a sixteenth of a thread's share, 256 to 2,048 beams) balance a
  // single long-range scan. With discretized end points a thread traces each end cell once, and
  // neighbouring beams share end cells across a chunk border: then four large chunks per thread
  // (two fixed halves were too uneven, a depth image's rows differing in cost).
  const std::size_t chunk = ip.discretize ? std::max<std::size_t>(2048, (count + 4 * threads - 1) / (4 * threads))
                                          : std::clamp<std::size_t>(count / (16 * threads), 256, 2048);
  ChunkClaims claims((count + chunk - 1) / chunk, threads);
  const Key origin_key = planar ? lattice_.key(origin) : Key{};
  const bool trace_free = ip.model == SensorModel::BeamBased;
  const auto trace = [&](std::size_t t) {
    try {
      InsertStats own;  // counted locally: neighbouring entries of `part` share a cache line
      if (planar) {
        scratch.planar_batches[t].reset(lo, hi);
      } else {
        scratch.batches[t].clear();
      }
      for (std::size_t c; (c = claims.next(t)) != ChunkClaims::kNone;) {
        const std::size_t first = c * chunk, n = std::min(chunk, count - first);
        const std::uint8_t* hits = is_hit ? is_hit + first : nullptr;
        if (planar) {
          PlanarBatch& batch = scratch.planar_batches[t];
          for (std::size_t i = first; i < first + n; ++i) {
            const PlanarBeam& beam = scratch.planar_beams[i];
            if (!beam.traced) continue;
            // With discretized ends, a beam to a cell already traced to in this batch adds nothing.
            if (beam.hit && !batch.markOccupied(beam.end) && ip.discretize) continue;
            if (trace_free) batch.markRayFree(beam.seg, origin_key, beam.skip_runs);
          }
        } else {
          traceBeams(origin, points + first, n, ip, hits, scratch.batches[t], own);
        }
      }
      if (planar) {
        scratch.planar_batches[t].finalize();
      } else {
        scratch.batches[t].finalize();
      }
      part[t] = own;
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  for (std::size_t t = 1; t < threads; ++t) workers.emplace_back(trace, t);
  trace(0);
  for (auto& w : workers) w.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  for (std::size_t t = 0; t < threads; ++t) stats += part[t];
  if (planar) {
    applyPlanar(threads, lo.z, stats);
  } else {
    std::vector<const UpdateBatch*> batches;
    for (std::size_t t = 0; t < threads; ++t) batches.push_back(&scratch.batches[t]);
    applyUpdate(batches, stats, static_cast<int>(threads));
  }
  return stats;
}

bool OccupancyMap::preparePlanarBeams(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                                      const InsertParams& ip, const std::uint8_t* is_hit, Key& lo, Key& hi,
                                      InsertStats& stats) {
  // A planar batch of more than this many bricks (16 MiB: a scan 400 m wide at 5 cm) takes
  // the general path instead.
  constexpr std::size_t kMaxPlanarTiles = std::size_t{1} << 18;
  Key origin_key;
  if (!lattice_.tryKey(origin, origin_key)) return false;
  const Eigen::Vector3d origin_l = lattice_.toLattice(origin);
  lo = hi = origin_key;
  // Grown beam by beam: a volumetric scan usually leaves the layer within its first beams, and
  // sizing for all of them (a depth image: 307,200) cost more than its whole planar test.
  std::vector<PlanarBeam>& beams = scratch_->planar_beams;
  beams.clear();
  InsertStats counts;  // into `stats` only if the scan is planar: else the general path counts
  Eigen::Vector3d end;
  for (std::size_t i = 0; i < count; ++i) {
    PlanarBeam& beam = beams.emplace_back();
    const BeamEnd kind = endOfBeam(lattice_, origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0,
                                   ip, end, beam.end);
    beam.traced = false;
    beam.skip_runs = 0;
    switch (kind) {
      case BeamEnd::NonFinite: ++counts.skipped_non_finite; continue;
      case BeamEnd::ZeroLength: ++counts.skipped_zero_length; continue;
      case BeamEnd::OutOfRange: ++counts.skipped_out_of_range; continue;
      case BeamEnd::TooLong: ++counts.skipped_too_long; continue;
      default: break;
    }
    if (beam.end.z != origin_key.z) return false;
    lo = Key{std::min(lo.x, beam.end.x), std::min(lo.y, beam.end.y), lo.z};
    hi = Key{std::max(hi.x, beam.end.x), std::max(hi.y, beam.end.y), hi.z};
    beam.traced = true;
    beam.hit = kind == BeamEnd::Hit;
    ++(beam.hit ? counts.rays_hit : counts.rays_truncated);
    const Eigen::Vector3d end_l = ip.discretize ? Eigen::Vector3d(beam.end.x + 0.5, beam.end.y + 0.5, beam.end.z + 0.5)
                                                : lattice_.toLattice(end);
    beam.seg = planarSegment(origin_l, end_l, origin_key, beam.end);
  }
  if (PlanarBatch::tilesFor(lo, hi) > kMaxPlanarTiles) return false;
  // Discretized beams are traced once per end cell, which a skip could not rely on.
  if (ip.model == SensorModel::BeamBased && !ip.discretize) fanSkipRuns(beams.data(), count);
  stats += counts;
  return true;
}

void OccupancyMap::computeUpdate(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                                 const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                                 InsertStats& stats) const {
  traceBeams(origin, points, count, ip, is_hit, batch, stats);
}

void OccupancyMap::traceBeams(const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t count,
                              const InsertParams& ip, const std::uint8_t* is_hit, UpdateBatch& batch,
                              InsertStats& stats) const {
  const Key origin_key = lattice_.key(origin);  // throws for a bad origin
  const Eigen::Vector3d origin_l = lattice_.toLattice(origin);
  const bool trace = ip.model == SensorModel::BeamBased;
  Eigen::Vector3d end;
  Key end_key;
  for (std::size_t i = 0; i < count; ++i) {
    const BeamEnd kind =
        endOfBeam(lattice_, origin, points[i].cast<double>(), is_hit == nullptr || is_hit[i] != 0, ip, end, end_key);
    switch (kind) {
      case BeamEnd::NonFinite: ++stats.skipped_non_finite; continue;
      case BeamEnd::ZeroLength: ++stats.skipped_zero_length; continue;
      case BeamEnd::OutOfRange: ++stats.skipped_out_of_range; continue;
      case BeamEnd::TooLong: ++stats.skipped_too_long; continue;
      default: break;
    }
    const bool hit = kind == BeamEnd::Hit;
    ++(hit ? stats.rays_hit : stats.rays_truncated);
    Eigen::Vector3d end_l;
    if (ip.discretize) {
      // A beam to a cell already traced to in this batch adds nothing.
      if (hit && !batch.markOccupied(end_key)) continue;
      end_l = Eigen::Vector3d(end_key.x + 0.5, end_key.y + 0.5, end_key.z + 0.5);
    } else {
      if (hit) batch.markOccupied(end_key);
      end_l = lattice_.toLattice(end);
    }
    if (trace) batch.queueRayFree(origin_l, end_l, origin_key, end_key);
  }
}

void OccupancyMap::applyUpdate(const UpdateBatch& batch, InsertStats& stats, int threads) {
  applyUpdate(std::vector<const UpdateBatch*>{&batch}, stats, threads);
}

// Group g has the updates sources[first[g] .. first[g + 1]) of brick slots[g]. The arrays are
// sized before grouping starts and never move: appliers read the groups published while later
// ones are written. What the grouper writes for every group (count), what the appliers poll
// (published) and the vectors' headers they read for every group lie on cache lines of their own,
// whatever the stack's offset: else each group's write would take the pollers' line away.
struct alignas(64) OccupancyMap::BrickGroups {
  static constexpr std::size_t kPublishEvery = 16;
  std::vector<const UpdateBatch::BrickUpdates*> sources;
  std::vector<std::uint32_t> first, slots;
  alignas(64) std::atomic<std::size_t> published{0};  // groups an applier may take
  std::atomic<bool> done{false};                      // `count` is final
  alignas(64) std::size_t count = 0;

  BrickGroups(std::size_t bricks, std::size_t updates) : sources(updates), first(bricks + 1, 0), slots(bricks) {}
  /// How many of groups [0, want) can be taken, waiting while they are being grouped; fewer
  /// only once grouping is done.
  std::size_t available(std::size_t want) const {
    for (unsigned spins = 0;; ++spins) {
      if (published.load(std::memory_order_acquire) >= want) return want;
      if (done.load(std::memory_order_acquire)) return std::min(want, count);
#if defined(__SSE2__)
      if (spins < 256) {
        _mm_pause();
        continue;
      }
#endif
      std::this_thread::yield();
    }
  }
};

namespace {

// A merge of finalized batches' brick lists (in Morton order): for each brick, in order, calls
// source(update) for every batch holding it, then group(brick). Codes and keys come from the
// batches' lists: reading them through the pointers would miss the cache once per brick, on
// data another thread wrote.
template <class Source, class Group>
void mergeBrickLists(const std::vector<const UpdateBatch*>& batches, Source&& source, Group&& group) {
  std::vector<std::size_t> pos(batches.size(), 0);
  for (;;) {
    std::size_t from = batches.size();
    for (std::size_t b = 0; b < batches.size(); ++b)
      if (pos[b] < batches[b]->brickCodes().size() &&
          (from == batches.size() || batches[b]->brickCodes()[pos[b]] < batches[from]->brickCodes()[pos[from]]))
        from = b;
    if (from == batches.size()) return;
    const std::uint64_t code = batches[from]->brickCodes()[pos[from]];
    const Key brick = batches[from]->brickKeys()[pos[from]];
    for (std::size_t b = 0; b < batches.size(); ++b)
      if (pos[b] < batches[b]->brickCodes().size() && batches[b]->brickCodes()[pos[b]] == code)
        source(batches[b]->bricks()[pos[b]++]);
    group(brick);
  }
}

}  // namespace

void OccupancyMap::groupByBrick(const std::vector<const UpdateBatch*>& batches, BrickGroups& groups) {
  std::uint32_t taken = 0;
  try {
    mergeBrickLists(
        batches, [&](const UpdateBatch::BrickUpdates* u) { groups.sources[taken++] = u; },
        [&](const Key& brick) {
          // Slots in brick order, whoever applies the groups: the map does not depend on the threads.
          groups.slots[groups.count] = brickSlot(brick);
          groups.first[++groups.count] = taken;
          if (groups.count % BrickGroups::kPublishEvery == 0)
            groups.published.store(groups.count, std::memory_order_release);
        });
  } catch (...) {
    // Appliers finish what was published; the caller rethrows after joining them.
    groups.count = groups.published.load(std::memory_order_relaxed);
    groups.done.store(true, std::memory_order_release);
    throw;
  }
  groups.published.store(groups.count, std::memory_order_release);
  groups.done.store(true, std::memory_order_release);
}

const UpdateBatch::BrickUpdates* OccupancyMap::unionOf(const UpdateBatch::BrickUpdates* const* sources, std::size_t n,
                                                       UpdateBatch::BrickUpdates& scratch) {
  if (n == 1) return sources[0];
  scratch = *sources[0];
  for (std::size_t s = 1; s < n; ++s)
    for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w) {
      scratch.occupied[w] |= sources[s]->occupied[w];
      scratch.free[w] |= sources[s]->free[w];
    }
  for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w) scratch.free[w] &= ~scratch.occupied[w];
  return &scratch;
}

void OccupancyMap::applyUpdate(const std::vector<const UpdateBatch*>& batches, InsertStats& stats, int threads) {
  if (threads < 1) throw std::invalid_argument("applyUpdate: threads must be >= 1");
  const ScratchScope scope(*this);
  std::vector<ApplyContext>& contexts = scratch_->apply_ctx;
  if (hasPendingCover()) flush();
  // Distinct bricks, counted ahead (a cheap pass over the key lists) for the room bricks_ needs:
  // it must not move while appliers hold bricks.
  std::size_t distinct = 0, updates = 0, largest = 0;
  for (const UpdateBatch* b : batches) {
    updates += b->bricks().size();
    largest = std::max(largest, b->bricks().size());
  }
  if (batches.size() == 1) {
    distinct = updates;
  } else {
    mergeBrickLists(batches, [](const UpdateBatch::BrickUpdates*) {}, [&](const Key&) { ++distinct; });
  }
  BrickGroups groups(distinct, updates);
  // Room for every brick being new (a first scan), still growing geometrically.
  if (bricks_.capacity() < bricks_.size() + distinct)
    bricks_.reserve(std::max(bricks_.size() + distinct, 2 * bricks_.capacity()));
  // Bricks are independent: threads take runs of them as they go (bricks near the sensor cost
  // far more than distant ones), each with its own scratch, while this thread still groups the
  // batches (serial: brick slots are given in brick order). The results do not depend on who
  // applied which brick: statistics are sums and refreshUpperTree() puts the reshaped bricks in
  // slot order where their order matters.
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(threads), 1 + largest / 64);
  if (contexts.size() < n) contexts.resize(n);
  constexpr std::size_t kGrain = 16;
  alignas(64) std::atomic<std::size_t> next_group{0};  // taken by every applier: a line of its own
  const auto work = [&](std::size_t t) {
    ApplyContext& ctx = contexts[t];
    ctx.local.assign(kBrickCells, -1);
    ctx.reshaped.clear();
    ctx.node_boxes.clear();
    ctx.reshaped_boxes.clear();
    ctx.leaf_delta = 0;
    ctx.stats = InsertStats{};
    for (std::size_t g = 0, e = 0;; ++g) {
      if (g == e) {
        g = next_group.fetch_add(kGrain, std::memory_order_relaxed);
        e = groups.available(g + kGrain);
        if (g >= e) break;
      }
      const std::uint32_t* first = &groups.first[g];
      applyBrick(*unionOf(&groups.sources[first[0]], first[1] - first[0], ctx.merged), groups.slots[g], ctx);
    }
  };
  std::vector<std::thread> workers;
  for (std::size_t t = 1; t < n; ++t) workers.emplace_back(work, t);
  try {
    groupByBrick(batches, groups);
  } catch (...) {
    for (auto& w : workers) w.join();
    throw;
  }
  work(0);
  for (auto& w : workers) w.join();
  reshaped_bricks_.clear();
  for (std::size_t t = 0; t < n; ++t) {
    stats += contexts[t].stats;
    leaf_count_ = static_cast<std::size_t>(static_cast<std::int64_t>(leaf_count_) + contexts[t].leaf_delta);
    reshaped_bricks_.insert(reshaped_bricks_.end(), contexts[t].reshaped.begin(), contexts[t].reshaped.end());
  }
  refreshUpperTree(static_cast<int>(n), contexts.data(), n);
}

void OccupancyMap::noteReshaped(std::uint32_t slot, ApplyContext& ctx) const {
  const std::vector<LeafEntry>& leaves = bricks_[slot].leaves;
  ctx.reshaped.push_back(slot);
  ctx.reshaped_boxes.push_back(static_cast<std::uint32_t>(ctx.node_boxes.size()));
  for (std::size_t k = 0; k * leafNodeSize() < leaves.size(); ++k) ctx.node_boxes.push_back(localNodeBox(leaves, k));
}

void OccupancyMap::refreshUpperTree(int threads, const ApplyContext* contexts, std::size_t context_count) {
  // Leaf nodes whose boxes changed go into the upper tree one by one, unless they are many
  // compared with the tree (a first scan, a new area): then one bulk load is cheaper.
  std::size_t touched_nodes = 0;
  for (const std::uint32_t slot : reshaped_bricks_)
    touched_nodes += (bricks_[slot].leaves.size() + leafNodeSize() - 1) / leafNodeSize();
  if (touched_nodes * 2 > upper_.size()) {
    rebuildUpperTree(threads, contexts, context_count);
  } else {
    // In slot order: the tree must not depend on which thread applied which brick.
    std::sort(reshaped_bricks_.begin(), reshaped_bricks_.end());
    for (const std::uint32_t slot : reshaped_bricks_) syncLeafNodes(slot);
  }
}

void OccupancyMap::rebuildUpperTree(int threads, const ApplyContext* contexts, std::size_t context_count) {
  // Leaf nodes go to the bulk load in Morton order of their bricks, and a brick's nodes follow
  // its leaves, which are in Morton order of their first cells when packed: close to the order
  // of the nodes' own Morton codes without sorting the nodes (one VLP-16 scan at 5 cm brings
  // 41,607 of them in 19,609 bricks, and the load runs on one thread).
  const auto slots = static_cast<std::uint32_t>(bricks_.size());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(slots);
  for (std::uint32_t slot = 0; slot < slots; ++slot) order[slot] = {mortonCode(bricks_[slot].brick), slot};
  // A first scan's bricks got their slots in this order already (update batches are in it).
  if (!std::is_sorted(order.begin(), order.end())) detail::radixSortByKey(order);
  // Handles are the nodes' positions in the load, so each brick knows its own before the load.
  std::vector<std::uint32_t> first_node(slots + 1, 0);
  for (std::uint32_t i = 0; i < slots; ++i) {
    const std::size_t n = (bricks_[order[i].second].leaves.size() + leafNodeSize() - 1) / leafNodeSize();
    first_node[i + 1] = first_node[i] + static_cast<std::uint32_t>(n);
  }
  std::vector<const LeafEntry*> boxes_of(context_count > 0 ? slots : 0, nullptr);  // taken when applied
  for (std::size_t c = 0; c < context_count; ++c)
    for (std::size_t i = 0; i < contexts[c].reshaped.size(); ++i)
      boxes_of[contexts[c].reshaped[i]] = contexts[c].node_boxes.data() + contexts[c].reshaped_boxes[i];
  std::vector<std::pair<Box, LeafNodeRef>> nodes(first_node[slots]);
  std::vector<std::uint32_t> rank(slots);  // of each slot in `order`
  for (std::uint32_t i = 0; i < slots; ++i) rank[order[i].second] = i;
  // The leaf nodes' boxes read every leaf of the map: the threads take ranges of slots, not of
  // `order`, whose neighbours' bricks (56 bytes, written here) would share cache lines.
  const std::uint32_t parts = std::max<std::uint32_t>(1, std::min<std::uint32_t>(threads, 1 + slots / 1024));
  const auto collect = [&](std::uint32_t p) {
    for (std::uint32_t slot = slots / parts * p; slot < (p + 1 == parts ? slots : slots / parts * (p + 1)); ++slot) {
      const std::uint32_t i = rank[slot];
      Brick& br = bricks_[slot];
      br.nodes.resize(first_node[i + 1] - first_node[i]);
      const LeafEntry* boxes = boxes_of.empty() ? nullptr : boxes_of[slot];
      const Key origin = brickOrigin(br.brick);
      for (std::uint32_t k = 0; k < br.nodes.size(); ++k) {
        br.nodes[k] = first_node[i] + k;
        nodes[br.nodes[k]] = {boxes ? globalBox(origin, boxes[k]) : leafNodeBox(br, k), LeafNodeRef{slot, k}};
      }
    }
  };
  std::vector<std::thread> workers;
  for (std::uint32_t p = 1; p < parts; ++p) workers.emplace_back(collect, p);
  collect(0);
  for (auto& w : workers) w.join();
  upper_.bulkLoad(std::move(nodes), RTree<LeafNodeRef>::Packing::AsGiven, threads);
}

namespace {

// Cuts `box` (brick-local, inclusive) around `cell` into at most six boxes that cover
// box minus cell: x-slabs first, then y-rows, then z-runs.
int cutAround(const std::uint8_t lo[3], const std::uint8_t hi[3], const Key& cell, std::uint8_t out_lo[6][3],
              std::uint8_t out_hi[6][3]) {
  int n = 0;
  std::uint8_t cur_lo[3] = {lo[0], lo[1], lo[2]}, cur_hi[3] = {hi[0], hi[1], hi[2]};
  for (int a = 0; a < 3; ++a) {
    const auto c = static_cast<std::uint8_t>(cell[a]);
    if (c > cur_lo[a]) {
      std::copy(cur_lo, cur_lo + 3, out_lo[n]);
      std::copy(cur_hi, cur_hi + 3, out_hi[n]);
      out_hi[n][a] = static_cast<std::uint8_t>(c - 1);
      ++n;
    }
    if (c < cur_hi[a]) {
      std::copy(cur_lo, cur_lo + 3, out_lo[n]);
      std::copy(cur_hi, cur_hi + 3, out_hi[n]);
      out_lo[n][a] = static_cast<std::uint8_t>(c + 1);
      ++n;
    }
    cur_lo[a] = cur_hi[a] = c;
  }
  return n;
}

template <class Fn>
void forEachLocal(const std::uint8_t lo[3], const std::uint8_t hi[3], Fn&& fn) {
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) fn(localIdx(x, y, z));
}

}  // namespace

// Local cell indices of a brick in Morton (Z-order) order, so that consecutive leaves, and
// with them the leaf nodes cut from them, stay compact.
static const std::array<std::uint16_t, kBrickCells>& mortonOrder() {
  static const std::array<std::uint16_t, kBrickCells> order = [] {
    std::array<std::uint16_t, kBrickCells> o{};
    for (int m = 0; m < kBrickCells; ++m) {
      int c[3] = {0, 0, 0};
      for (int bit = 0; bit < kBrickBits; ++bit)
        for (int a = 0; a < 3; ++a) c[a] |= ((m >> (3 * bit + a)) & 1) << bit;
      o[static_cast<std::size_t>(m)] = static_cast<std::uint16_t>(localIdx(c[0], c[1], c[2]));
    }
    return o;
  }();
  return order;
}

// Inverse of mortonOrder(): the Morton rank of each local cell index.
static const std::array<std::uint16_t, kBrickCells>& mortonRank() {
  static const std::array<std::uint16_t, kBrickCells> rank = [] {
    std::array<std::uint16_t, kBrickCells> r{};
    const auto& order = mortonOrder();
    for (std::size_t m = 0; m < order.size(); ++m) r[order[m]] = static_cast<std::uint16_t>(m);
    return r;
  }();
  return rank;
}

// Replaces `to` by the leaves of `from` in Morton order of their first cells, which keeps the
// leaf nodes cut from the array compact. Disjoint boxes have distinct first cells, so a bit per
// rank sorts them in O(n + 64 words). Scratch on the stack: thread_local would cost a TLS call
// per brick in a shared library.
template <class Leaves, class Out>
static void assignByFirstCell(const Leaves& from, Out& to) {
  const auto& rank = mortonRank();
  std::array<std::uint64_t, kBrickWords> present{};
  std::array<std::uint32_t, kBrickCells> index_at;  // read only where `present` is set
  for (std::size_t i = 0; i < from.size(); ++i) {
    const auto& e = from[i];
    const std::uint16_t r = rank[static_cast<std::size_t>(localIdx(e.lo[0], e.lo[1], e.lo[2]))];
    present[r >> 6] |= std::uint64_t{1} << (r & 63);
    index_at[r] = static_cast<std::uint32_t>(i);
  }
  to.clear();
  to.reserve(from.size());
  for (std::size_t w = 0; w < kBrickWords; ++w)
    for (std::uint64_t bits = present[w]; bits; bits &= bits - 1)
      to.push_back(from[index_at[w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits))]]);
}

namespace {

// Writes `leaf` into the scratch table over its box and sets the box's bits in `painted`.
void paintLeaf(const std::uint8_t lo[3], const std::uint8_t hi[3], std::int32_t leaf, std::vector<std::int32_t>& local,
               BrickMask& painted) {
  const std::uint64_t run = xRun(lo[0], hi[0]);
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y) {
      const int base = localIdx(0, y, z);
      for (int x = lo[0]; x <= hi[0]; ++x) local[static_cast<std::size_t>(base + x)] = leaf;
      painted[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
    }
}

}  // namespace

void OccupancyMap::applyBrick(const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx) {
  std::vector<LeafEntry>& leaves = bricks_[slot].leaves;
  std::vector<std::int32_t>& local = ctx.local;
  InsertStats& stats = ctx.stats;
  const std::size_t updates_occupied = maskPopcount(upd.occupied), updates_free = maskPopcount(upd.free);
  stats.cells_occupied += updates_occupied;
  stats.cells_free += updates_free;
  // Past this many updates one pass over the brick beats splitting and re-merging per cell
  // (measured on the TUM frames). Only equal-value merging churns so: clamped cuboids absorb
  // most updates unchanged.
  constexpr std::size_t kRebuildUpdates = 128;
  if (params_.merge == MergePolicy::Equal && leaves.empty()) {
    coverFreshBrick(upd, slot, ctx);
    return;
  }
  if (params_.merge == MergePolicy::Equal && updates_occupied + updates_free >= kRebuildUpdates) {
    rebuildBrick(upd, slot, ctx);
    return;
  }
  BrickMask known{};
  for (std::size_t i = 0; i < leaves.size(); ++i)
    paintLeaf(leaves[i].lo, leaves[i].hi, static_cast<std::int32_t>(i), local, known);

  const bool merging = params_.merge != MergePolicy::Off;
  const std::size_t leaves_before = leaves.size();
  bool reshaped = false;
  std::vector<std::uint32_t>& candidates = ctx.candidates;
  candidates.clear();
  // Cells seen for the first time: all of a class get the same value, so they go in as boxes.
  const auto addFresh = [&](const BrickMask& mask, float delta) {
    const float v = model_.first(delta);
    const bool boxes = merging && mergeable(v);
    const auto add = [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int /*start*/ = 0) {
      leaves.push_back(LeafEntry{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, v});
      const auto li = static_cast<std::int32_t>(leaves.size() - 1);
      paintLeaf(lo, hi, li, local, known);
      if (boxes) candidates.push_back(static_cast<std::uint32_t>(li));
    };
    if (boxes) {
      coverGreedily(mask, [](int, int) { return true; }, add);
      return;
    }
    for (int w = 0; w < kBrickWords; ++w)
      for (std::uint64_t bits = mask[static_cast<std::size_t>(w)]; bits; bits &= bits - 1) {
        const Key lk = localKey(w * 64 + __builtin_ctzll(bits));
        const std::uint8_t c[3] = {static_cast<std::uint8_t>(lk.x), static_cast<std::uint8_t>(lk.y),
                                   static_cast<std::uint8_t>(lk.z)};
        add(c, c);
      }
  };
  BrickMask fresh_occ, fresh_free;
  for (std::size_t w = 0; w < static_cast<std::size_t>(kBrickWords); ++w) {
    fresh_occ[w] = upd.occupied[w] & ~known[w];
    fresh_free[w] = upd.free[w] & ~upd.occupied[w] & ~known[w];
  }
  for (int w = 0; w < kBrickWords; ++w) {
    std::uint64_t bits = (upd.occupied[w] | upd.free[w]) & known[w];
    while (bits) {
      const int b = __builtin_ctzll(bits);
      bits &= bits - 1;
      const int idx = w * 64 + b;
      const float delta = (upd.occupied[w] >> b) & 1u ? model_.hitDelta() : model_.missDelta();
      const Key lk = localKey(idx);
      const std::int32_t li = local[idx];
      LeafEntry& e = leaves[static_cast<std::size_t>(li)];
      const float old = e.value;
      const float v = model_.update(old, delta);
      if (v == old) {
        ++stats.cells_unchanged;
        continue;
      }
      e.value = v;
      if (merging && mergeable(v)) candidates.push_back(static_cast<std::uint32_t>(li));
      if (e.lo[0] == e.hi[0] && e.lo[1] == e.hi[1] && e.lo[2] == e.hi[2]) continue;

      // Disagreeing evidence inside a merged cuboid: the leaf shrinks to the updated cell
      // and the rest of its cells keep the old value in at most six new leaves.
      std::uint8_t plo[6][3], phi[6][3];
      const LeafEntry whole = e;
      const int pieces = cutAround(whole.lo, whole.hi, lk, plo, phi);
      for (int a = 0; a < 3; ++a) e.lo[a] = e.hi[a] = static_cast<std::uint8_t>(lk[a]);
      for (int p = 0; p < pieces; ++p) {
        leaves.push_back(LeafEntry{{plo[p][0], plo[p][1], plo[p][2]}, {phi[p][0], phi[p][1], phi[p][2]}, old});
        const auto pi = static_cast<std::int32_t>(leaves.size() - 1);
        forEachLocal(plo[p], phi[p], [&](int i) { local[i] = pi; });
        candidates.push_back(static_cast<std::uint32_t>(pi));  // was merged, so mergeable
      }
      ++stats.leaves_split;
      reshaped = true;
    }
  }
  addFresh(fresh_occ, model_.hitDelta());
  addFresh(fresh_free, model_.missDelta());
  stats.leaves_created += leaves.size() - leaves_before;
  if (merging && !candidates.empty()) {
    const std::size_t merges = mergeInBrick(leaves, local, candidates);
    stats.leaves_merged += merges;
    reshaped |= merges > 0;
  }
  if (reshaped || leaves.size() != leaves_before) {
    // Leaves merged away are replaced by the last ones, new leaves were appended: only the
    // leaf nodes at those places change, and syncLeafNodes() updates just those boxes.
    for (std::size_t i = 0; i < leaves.size();) {
      if (leaves[i].lo[0] == kDead) {
        leaves[i] = leaves.back();
        leaves.pop_back();
      } else {
        ++i;
      }
    }
    if (leaves.capacity() > 2 * leaves.size() + 16) leaves.shrink_to_fit();
    noteReshaped(slot, ctx);
  }
  ctx.leaf_delta += static_cast<std::int64_t>(leaves.size()) - static_cast<std::int64_t>(leaves_before);
  // Leave the scratch table empty for the next brick; only painted cells need it.
  for (const LeafEntry& e : leaves) forEachLocal(e.lo, e.hi, [&](int idx) { local[idx] = -1; });
}

void OccupancyMap::coverFreshBrick(const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx) {
  std::vector<LeafEntry>& out = ctx.rebuilt;
  out.clear();
  for (const bool occupied : {true, false}) {
    const float v = model_.first(occupied ? model_.hitDelta() : model_.missDelta());
    coverGreedily(
        occupied ? upd.occupied : upd.free, [](int, int) { return true; },
        [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int) {
          out.push_back(LeafEntry{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, v});
        });
  }
  ctx.stats.leaves_created += out.size();
  ctx.leaf_delta += static_cast<std::int64_t>(out.size());
  assignByFirstCell(out, bricks_[slot].leaves);
  noteReshaped(slot, ctx);
}

void OccupancyMap::rebuildBrick(const UpdateBatch::BrickUpdates& upd, std::uint32_t slot, ApplyContext& ctx) {
  std::vector<LeafEntry>& leaves = bricks_[slot].leaves;
  std::vector<float>& value = ctx.values;
  value.resize(kBrickCells);
  InsertStats& stats = ctx.stats;
  BrickMask known{}, changed{};
  for (const LeafEntry& e : leaves) {
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    for (int z = e.lo[2]; z <= e.hi[2]; ++z)
      for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
        const int base = localIdx(0, y, z);
        for (int x = e.lo[0]; x <= e.hi[0]; ++x) value[static_cast<std::size_t>(base + x)] = e.value;
        known[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
      }
  }
  for (int w = 0; w < kBrickWords; ++w) {
    const auto wi = static_cast<std::size_t>(w);
    for (std::uint64_t bits = upd.occupied[wi] | upd.free[wi]; bits; bits &= bits - 1) {
      const int b = __builtin_ctzll(bits);
      const auto idx = static_cast<std::size_t>(w * 64 + b);
      const std::uint64_t bit = std::uint64_t{1} << b;
      const float delta = (upd.occupied[wi] & bit) ? model_.hitDelta() : model_.missDelta();
      if (known[wi] & bit) {
        const float v = model_.update(value[idx], delta);
        if (v == value[idx]) {
          ++stats.cells_unchanged;
          continue;
        }
        value[idx] = v;
      } else {
        value[idx] = model_.first(delta);
        known[wi] |= bit;
      }
      changed[wi] |= bit;
    }
  }
  // Old cuboids that now disagree inside are the splits of this pass.
  for (const LeafEntry& e : leaves) {
    if (e.lo[0] == e.hi[0] && e.lo[1] == e.hi[1] && e.lo[2] == e.hi[2]) continue;
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    bool hit = false;
    for (int z = e.lo[2]; z <= e.hi[2] && !hit; ++z)
      for (int y = e.lo[1]; y <= e.hi[1] && !hit; ++y) {
        const int base = localIdx(0, y, z);
        hit = (changed[static_cast<std::size_t>(base >> 6)] >> (base & 63)) & run;
      }
    stats.leaves_split += hit;
  }
  // Cover the known cells again with boxes of bit-identical (so lossless), mergeable values.
  std::vector<LeafEntry>& out = ctx.rebuilt;
  out.clear();
  coverGreedily(
      known,
      [&](int start, int cell) {
        const float v = value[static_cast<std::size_t>(start)];
        return value[static_cast<std::size_t>(cell)] == v && mergeable(v);
      },
      [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
        out.push_back(LeafEntry{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, value[static_cast<std::size_t>(start)]});
      });
  stats.leaves_created += out.size();
  stats.leaves_merged += leaves.size();
  ctx.leaf_delta += static_cast<std::int64_t>(out.size()) - static_cast<std::int64_t>(leaves.size());
  assignByFirstCell(out, leaves);
  noteReshaped(slot, ctx);
}

std::size_t OccupancyMap::mergeInBrick(std::vector<LeafEntry>& leaves, std::vector<std::int32_t>& local,
                                       const std::vector<std::uint32_t>& candidates) const {
  std::size_t merges = 0;
  for (const std::uint32_t i : candidates) {
    for (bool merged = true; merged;) {
      merged = false;
      LeafEntry& a = leaves[i];
      if (a.lo[0] == kDead || !mergeable(a.value)) break;
      for (int axis = 0; axis < 3 && !merged; ++axis) {
        const int b1 = (axis + 1) % 3, b2 = (axis + 2) % 3;
        for (int dir = 1; dir >= -1 && !merged; dir -= 2) {
          const int c = dir > 0 ? a.hi[axis] + 1 : a.lo[axis] - 1;
          if (c < 0 || c >= kBrickSize) continue;
          int n[3] = {a.lo[0], a.lo[1], a.lo[2]};
          n[axis] = c;
          const std::int32_t j = local[localIdx(n[0], n[1], n[2])];
          if (j < 0 || static_cast<std::uint32_t>(j) == i) continue;
          LeafEntry& nb = leaves[static_cast<std::size_t>(j)];
          // A face neighbour holding the cell next to a's corner starts right after a on
          // this axis (leaves are disjoint); it merges if its face matches exactly.
          if (nb.lo[b1] != a.lo[b1] || nb.hi[b1] != a.hi[b1] || nb.lo[b2] != a.lo[b2] || nb.hi[b2] != a.hi[b2])
            continue;
          if (nb.value != a.value) continue;
          forEachLocal(nb.lo, nb.hi, [&](int idx) { local[idx] = static_cast<std::int32_t>(i); });
          a.lo[axis] = std::min(a.lo[axis], nb.lo[axis]);
          a.hi[axis] = std::max(a.hi[axis], nb.hi[axis]);
          nb.lo[0] = kDead;
          ++merges;
          merged = true;
        }
      }
    }
  }
  return merges;
}

void OccupancyMap::packLeaves(std::uint32_t slot) {
  Brick& br = bricks_[slot];
  std::vector<LeafEntry>& live = pack_scratch_;
  live.clear();
  std::vector<LeafEntry> packed;  // exact capacity
  if (br.leaves.size() * 16 >= static_cast<std::size_t>(kBrickCells)) {
    // Dense brick: one pass over the cells in Morton order. The scratch table names each live
    // leaf at its first cell; dead leaves were repainted.
    for (const std::uint16_t idx : mortonOrder()) {
      const std::int32_t i = local_[idx];
      if (i < 0) continue;
      const LeafEntry& e = br.leaves[static_cast<std::size_t>(i)];
      if (localIdx(e.lo[0], e.lo[1], e.lo[2]) == idx) live.push_back(e);
    }
    packed.assign(live.begin(), live.end());
  } else {
    // Sparse brick: the few live leaves by the Morton rank of their first cell.
    for (const LeafEntry& e : br.leaves)
      if (e.lo[0] != kDead) live.push_back(e);
    assignByFirstCell(live, packed);
  }
  br.leaves.swap(packed);
}

void OccupancyMap::syncLeafNodes(std::uint32_t slot) {
  Brick& br = bricks_[slot];
  const std::size_t nodes = (br.leaves.size() + leafNodeSize() - 1) / leafNodeSize();
  for (std::size_t n = 0; n < nodes; ++n) {
    const Box box = leafNodeBox(br, n);
    if (n < br.nodes.size()) {
      if (upper_.box(br.nodes[n]) != box) upper_.updateBox(br.nodes[n], box);
    } else {
      br.nodes.push_back(upper_.insert(box, LeafNodeRef{slot, static_cast<std::uint32_t>(n)}));
    }
  }
  while (br.nodes.size() > nodes) {
    upper_.remove(br.nodes.back());
    br.nodes.pop_back();
  }
}

// ---- planar cache ------------------------------------------------------------------------

std::uint32_t OccupancyMap::planarLayer(std::uint32_t slot, int z) {
  const auto next = static_cast<std::uint32_t>(planar_layers_.size());
  const std::uint32_t index = planar_index_.findOrInsert(std::uint64_t{slot} * kBrickSize + static_cast<std::uint64_t>(z), next);
  if (index != next) return index;
  PlanarLayer& layer = planar_layers_.emplaceBack();
  layer.slot = slot;
  layer.z = z;
  layer.known.fill(0);
  layer.value.fill(model_.prior());
  // The layer's cells as the leaves crossing it hold them.
  for (const LeafEntry& e : bricks_[slot].leaves) {
    if (z < e.lo[2] || z > e.hi[2]) continue;
    const std::uint64_t run = xRun(e.lo[0], e.hi[0]);
    for (int y = e.lo[1]; y <= e.hi[1]; ++y) {
      const int base = y * kBrickSize;
      for (int x = e.lo[0]; x <= e.hi[0]; ++x) layer.value[static_cast<std::size_t>(base + x)] = e.value;
      layer.known[static_cast<std::size_t>(base >> 6)] |= run << (base & 63);
    }
  }
  return next;
}

void OccupancyMap::applyPlanar(std::size_t batches, int z, InsertStats& stats) {
  const std::vector<PlanarBatch>& planar_batches = scratch_->planar_batches;
  const PlanarBatch& b0 = planar_batches[0];
  const float deltas[4] = {model_.hitDelta(), model_.missDelta(), model_.clampMin(), model_.clampMax()};
  const int local_z = z & (kBrickSize - 1);
  static const detail::UpdateLayerFn update_layer = [] {
    const auto kernels = detail::layerUpdateKernels();
    return kernels[1] ? kernels[1] : kernels[0];
  }();
  detail::LayerCounts counts;
  for (std::size_t t = 0; t < b0.tiles().size(); ++t) {
    // The union over the threads' batches, occupied winning.
    PlanarBatch::Tile tile = b0.tiles()[t];
    for (std::size_t k = 1; k < batches; ++k)
      for (int w = 0; w < kLayerWords; ++w) {
        tile.occupied[static_cast<std::size_t>(w)] |= planar_batches[k].tiles()[t].occupied[static_cast<std::size_t>(w)];
        tile.free[static_cast<std::size_t>(w)] |= planar_batches[k].tiles()[t].free[static_cast<std::size_t>(w)];
      }
    std::uint64_t any = 0;
    for (int w = 0; w < kLayerWords; ++w) any |= tile.occupied[static_cast<std::size_t>(w)] | tile.free[static_cast<std::size_t>(w)];
    if (any == 0) continue;
    const auto width = static_cast<std::size_t>(b0.width());
    const Key brick{b0.brickX0() + static_cast<int>(t % width), b0.brickY0() + static_cast<int>(t / width),
                    z >> kBrickBits};
    // Most of a scan's tiles were layers of the scans before: recent ones skip the brick and
    // layer hash lookups.
    PlanarLayer& layer = planar_layers_[recent_layers_.get(packKey(Key{brick.x, brick.y, z}), [&] {
      return planarLayer(brickSlot(brick), local_z);
    })];
    // Unknown cells hold the prior, so a first update is an update like any other.
    update_layer(layer.value.data(), layer.known.data(), tile.occupied.data(), tile.free.data(), deltas, counts);
  }
  stats.cells_unchanged += counts.unchanged;
  stats.cells_free += counts.free;
  stats.cells_occupied += counts.occupied;
  if (!planar_layers_.empty()) cover_pending_.store(true, std::memory_order_release);
}

InsertStats OccupancyMap::coverPlanarLayers() {
  InsertStats stats;
  if (planar_layers_.empty()) return stats;
  // A brick's layers together, bricks in slot order (deterministic whatever the scans' order).
  std::vector<std::uint32_t> order(planar_layers_.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const PlanarLayer &la = planar_layers_[a], &lb = planar_layers_[b];
    return la.slot != lb.slot ? la.slot < lb.slot : la.z < lb.z;
  });
  const ScratchScope scope(*this);
  if (scratch_->apply_ctx.empty()) scratch_->apply_ctx.resize(1);
  std::vector<LeafEntry>& out = scratch_->apply_ctx[0].rebuilt;
  reshaped_bricks_.clear();
  for (std::size_t i = 0; i < order.size();) {
    const std::uint32_t slot = planar_layers_[order[i]].slot;
    const PlanarLayer* layer_at[kBrickSize] = {};
    BrickMask known{};
    int layers = 0;
    for (; i < order.size() && planar_layers_[order[i]].slot == slot; ++i, ++layers) {
      const PlanarLayer& layer = planar_layers_[order[i]];
      layer_at[layer.z] = &layer;
      std::copy(layer.known.begin(), layer.known.end(), known.begin() + layer.z * kLayerWords);
    }
    // Leaves outside the cached layers stay; those crossing them keep their parts outside.
    std::vector<LeafEntry>& leaves = bricks_[slot].leaves;
    out.clear();
    for (const LeafEntry& e : leaves) {
      bool crosses = false;
      for (int z = e.lo[2]; z <= e.hi[2] && !crosses; ++z) crosses = layer_at[z] != nullptr;
      if (!crosses) {
        out.push_back(e);
        continue;
      }
      for (int z = e.lo[2]; z <= e.hi[2]; ++z) {
        if (layer_at[z]) continue;
        int z1 = z;
        while (z1 + 1 <= e.hi[2] && !layer_at[z1 + 1]) ++z1;
        LeafEntry piece = e;
        piece.lo[2] = static_cast<std::uint8_t>(z);
        piece.hi[2] = static_cast<std::uint8_t>(z1);
        out.push_back(piece);
        ++stats.leaves_created;
        z = z1;
      }
      ++stats.leaves_merged;
    }
    const auto valueAt = [&](int cell) { return layer_at[cell / kLayerCells]->value[static_cast<std::size_t>(cell % kLayerCells)]; };
    const std::size_t kept = out.size();
    if (layers == 1) {
      const PlanarLayer& layer = planar_layers_[order[i - 1]];
      coverLayer(
          layer.known, layer.value.data(), layer.z, [&](float v) { return mergeable(v); },
          [&](const std::uint8_t lo[3], const std::uint8_t hi[3], float v) {
            out.push_back(LeafEntry{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, v});
          });
    } else {
      coverGreedily(
          known,
          [&](int start, int cell) {
            const float v = valueAt(start);
            return valueAt(cell) == v && mergeable(v);
          },
          [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
            out.push_back(LeafEntry{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, valueAt(start)});
          });
    }
    stats.leaves_created += out.size() - kept;
    leaf_count_ = leaf_count_ + out.size() - leaves.size();
    assignByFirstCell(out, leaves);
    reshaped_bricks_.push_back(slot);
  }
  refreshUpperTree();
  // Keep room for the layers of a scan or two (a 2D scan at 5 cm touches about 200), not for
  // those of a whole log: the pool counts in memoryBytes().
  constexpr std::size_t kKeptLayers = 512;
  recent_layers_.clear();
  if (planar_layers_.capacity() > kKeptLayers) {
    planar_layers_.release();
    planar_index_ = detail::FlatHashMap64();
  } else {
    planar_layers_.clear();
    planar_index_.clear();
  }
  return stats;
}

InsertStats OccupancyMap::flush() {
  // Under the lock, so that concurrent readers cover once: the later ones find no layers.
  std::lock_guard<std::mutex> lock(cover_mutex_);
  const InsertStats stats = coverPlanarLayers();
  cover_pending_.store(false, std::memory_order_release);
  return stats;
}

}  // namespace rtog
