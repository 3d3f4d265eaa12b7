#include "rtog/core/update_batch.hpp"

#include "rtog/core/detail/radix_sort.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <type_traits>
#include <numeric>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace rtog {

void UpdateBatch::clear() {
  packed_keys_.clear();
  index_.clear();
  sorted_.clear();
  sorted_keys_.clear();
  sorted_codes_.clear();
  cached_ = nullptr;
  recent_.clear();
  queued_.clear();
}

std::uint32_t UpdateBatch::brickSlot(const Key& b) {
  const auto next = static_cast<std::uint32_t>(packed_keys_.size());
  const std::uint64_t packed = packKey(b);
  const std::uint32_t slot = index_.findOrInsert(packed, next);
  if (slot == next) {
    if (next == chunks_.size() * kChunkBricks) chunks_.push_back(std::make_unique<Chunk>());
    packed_keys_.push_back(packed);
    BrickUpdates& u = brickAt(slot);
    u.brick = b;
    u.occupied.fill(0);
    u.free.fill(0);
    u.any_occupied = false;
  }
  return slot;
}

void UpdateBatch::markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                              const Key& to_key) {
  // Tracks the cell's brick and bit incrementally: a carry out of the brick's local range is
  // the only time the brick is looked up again. The walk does not move past its last visit, so
  // no brick enters the batch without a mark.
  struct BrickCursor {
    UpdateBatch& batch;
    Key cell;
    int local[3];
    std::uint64_t* words;
    void visit() {
      const int i = local[0] | (local[1] << kBrickBits) | (local[2] << (2 * kBrickBits));
      words[i >> 6] |= std::uint64_t{1} << (i & 63);
    }
    void move(int axis, int s) {
      cell[axis] += s;
      local[axis] += s;
      if (local[axis] & ~(kBrickSize - 1)) {
        local[axis] &= kBrickSize - 1;
        words = batch.brickFor(cell).free.data();
      }
    }
  };
  if (from_key == to_key) return;
  constexpr int m = kBrickSize - 1;
  BrickCursor cursor{*this, from_key, {from_key.x & m, from_key.y & m, from_key.z & m}, brickFor(from_key).free.data()};
  walkRay(from, to, from_key, to_key, cursor);
}

namespace {

#if defined(__x86_64__)
// Window geometry: bricks along each axis a power of two, so that a step into the next brick
// moves a word offset by a shift of the step.
struct Window {
  Key origin;   // brick coordinates of the window's first brick
  int bits[3];  // log2 of the bricks along each axis
  std::size_t bricks() const { return std::size_t{1} << (bits[0] + bits[1] + bits[2]); }
  std::int64_t wordOffset(const Key& cell) const {
    const std::int64_t bx = (cell.x >> kBrickBits) - origin.x, by = (cell.y >> kBrickBits) - origin.y,
                       bz = (cell.z >> kBrickBits) - origin.z;
    return ((bz << (bits[0] + bits[1])) | (by << bits[0]) | bx) * kBrickWords;
  }
};

constexpr double kInf = std::numeric_limits<double>::infinity();

// One ray in walkRay's floating-point form (its 3D branch): a lane's state.
struct LaneRay {
  double t[3], dt[3];
  std::int64_t left[3];  // steps left along each axis
  std::int64_t dir[3];
  std::int64_t local[3];  // the current cell in its brick
  std::int64_t word;      // window word offset of the current cell's brick
  std::int64_t steps;
};

void setUpLane(const UpdateBatch::QueuedRay& q, const Window& w, LaneRay& r) {
  int step[3];
  r.steps = detail::setUpWalk(q.from, q.to, q.from_key, q.to_key, step, r.t, r.dt);
  for (int a = 0; a < 3; ++a) {
    const std::int64_t diff = std::int64_t{q.to_key[a]} - q.from_key[a];
    r.left[a] = diff < 0 ? -diff : diff;
    r.dir[a] = step[a];
    r.local[a] = q.from_key[a] & (kBrickSize - 1);
  }
  r.word = w.wordOffset(q.from_key);
}

// Eight rays in two groups of four AVX2 lanes: each step is branch-free (the axis by compares
// and blends, a brick change by a shifted carry), so the two groups' dependency chains overlap
// instead of waiting on mispredicted branches. A lane whose ray ends takes the next ray.
// `touched` gets a non-zero byte for each brick marked (index: word offset / 64), so that only
// those are swept.
__attribute__((target("avx2"))) void walkLanes(const std::vector<UpdateBatch::QueuedRay>& queued,
                                               const std::vector<std::uint32_t>& rays, const Window& w,
                                               std::uint64_t* window, std::uint8_t* touched) {
  constexpr int kGroups = 2, kLanes = 4 * kGroups;
  alignas(32) double t[kGroups][3][4], dt[kGroups][3][4];
  alignas(32) std::int64_t left[kGroups][3][4], dir[kGroups][3][4], local[kGroups][3][4], word[kGroups][4];
  std::int64_t steps[kLanes];
  std::size_t next = 0;
  int live = 0;
  // A lane without a ray stands still (no direction, no axis ever at its end) and marks a
  // scratch brick just before the window.
  const auto load = [&](int lane) {
    const int g = lane / 4, j = lane % 4;
    if (next < rays.size()) {  // queued rays leave their z-layer: at least one step
      LaneRay r;
      setUpLane(queued[rays[next++]], w, r);
      for (int a = 0; a < 3; ++a) {
        t[g][a][j] = r.t[a];
        dt[g][a][j] = r.dt[a];
        left[g][a][j] = r.left[a];
        dir[g][a][j] = r.dir[a];
        local[g][a][j] = r.local[a];
      }
      word[g][j] = r.word;
      steps[lane] = r.steps;
      return true;
    }
    for (int a = 0; a < 3; ++a) {
      t[g][a][j] = dt[g][a][j] = 0.0;
      left[g][a][j] = -1;
      dir[g][a][j] = local[g][a][j] = 0;
    }
    word[g][j] = -kBrickWords;  // marks go to the scratch brick in front of the window
    steps[lane] = std::numeric_limits<std::int64_t>::max();
    return false;
  };
  for (int lane = 0; lane < kLanes; ++lane) live += load(lane);
  const __m256d inf = _mm256_set1_pd(kInf);
  const __m256i low4 = _mm256_set1_epi64x(kBrickSize - 1), zero = _mm256_setzero_si256(),
                one = _mm256_set1_epi64x(1), low6 = _mm256_set1_epi64x(63), all = _mm256_set1_epi64x(-1);
  const __m128i carry_shift[3] = {_mm_cvtsi32_si128(6), _mm_cvtsi32_si128(6 + w.bits[0]),
                                  _mm_cvtsi32_si128(6 + w.bits[0] + w.bits[1])};
  while (live > 0) {
    __m256d T[kGroups][3];
    __m256i left_v[kGroups][3], local_v[kGroups][3], word_v[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      for (int a = 0; a < 3; ++a) {
        T[g][a] = _mm256_load_pd(t[g][a]);
        left_v[g][a] = _mm256_load_si256(reinterpret_cast<const __m256i*>(left[g][a]));
        local_v[g][a] = _mm256_load_si256(reinterpret_cast<const __m256i*>(local[g][a]));
      }
      word_v[g] = _mm256_load_si256(reinterpret_cast<const __m256i*>(word[g]));
    }
    std::int64_t run = steps[0];
    for (int lane = 1; lane < kLanes; ++lane) run = std::min(run, steps[lane]);
    for (std::int64_t step = 0; step < run; ++step)
      for (int g = 0; g < kGroups; ++g) {
        const __m256i cell = _mm256_or_si256(
            local_v[g][0], _mm256_or_si256(_mm256_slli_epi64(local_v[g][1], kBrickBits),
                                           _mm256_slli_epi64(local_v[g][2], 2 * kBrickBits)));
        const __m256i at = _mm256_add_epi64(word_v[g], _mm256_srli_epi64(cell, 6));
        const __m256i bit = _mm256_sllv_epi64(one, _mm256_and_si256(cell, low6));
        const __m128i at_lo = _mm256_castsi256_si128(at), at_hi = _mm256_extracti128_si256(at, 1);
        const __m128i bit_lo = _mm256_castsi256_si128(bit), bit_hi = _mm256_extracti128_si256(bit, 1);
        const std::int64_t at0 = _mm_cvtsi128_si64(at_lo), at1 = _mm_extract_epi64(at_lo, 1),
                           at2 = _mm_cvtsi128_si64(at_hi), at3 = _mm_extract_epi64(at_hi, 1);
        window[at0] |= static_cast<std::uint64_t>(_mm_cvtsi128_si64(bit_lo));
        window[at1] |= static_cast<std::uint64_t>(_mm_extract_epi64(bit_lo, 1));
        window[at2] |= static_cast<std::uint64_t>(_mm_cvtsi128_si64(bit_hi));
        window[at3] |= static_cast<std::uint64_t>(_mm_extract_epi64(bit_hi, 1));
        touched[at0 >> 6] = touched[at1 >> 6] = touched[at2 >> 6] = touched[at3 >> 6] = 1;
        // walkRay's choice: x if tx <= ty and tx <= tz, else y if ty <= tz, else z.
        const __m256d x_first = _mm256_and_pd(_mm256_cmp_pd(T[g][0], T[g][1], _CMP_LE_OQ),
                                              _mm256_cmp_pd(T[g][0], T[g][2], _CMP_LE_OQ));
        const __m256d y_first = _mm256_andnot_pd(x_first, _mm256_cmp_pd(T[g][1], T[g][2], _CMP_LE_OQ));
        const __m256d z_first = _mm256_andnot_pd(_mm256_or_pd(x_first, y_first), _mm256_castsi256_pd(all));
        const __m256d chosen[3] = {x_first, y_first, z_first};
        for (int a = 0; a < 3; ++a) {
          const __m256i step_mask = _mm256_castpd_si256(chosen[a]);
          left_v[g][a] = _mm256_add_epi64(left_v[g][a], step_mask);  // -1 where this axis steps
          const __m256d at_end = _mm256_castsi256_pd(_mm256_cmpeq_epi64(left_v[g][a], zero));
          const __m256d next_t =
              _mm256_blendv_pd(_mm256_add_pd(T[g][a], _mm256_load_pd(dt[g][a])), inf, at_end);
          T[g][a] = _mm256_blendv_pd(T[g][a], next_t, chosen[a]);
          const __m256i moved = _mm256_add_epi64(
              local_v[g][a],
              _mm256_and_si256(_mm256_load_si256(reinterpret_cast<const __m256i*>(dir[g][a])), step_mask));
          // Out of the brick: moved >> 4 is 1, or for -1 all ones but the top four bits, which the
          // shift by the axis's word stride (>= 6 bits) pushes out, leaving minus that stride.
          word_v[g] = _mm256_add_epi64(word_v[g], _mm256_sll_epi64(_mm256_srli_epi64(moved, kBrickBits),
                                                                   carry_shift[a]));
          local_v[g][a] = _mm256_and_si256(moved, low4);
        }
      }
    for (int g = 0; g < kGroups; ++g) {
      for (int a = 0; a < 3; ++a) {
        _mm256_store_pd(t[g][a], T[g][a]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(left[g][a]), left_v[g][a]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(local[g][a]), local_v[g][a]);
      }
      _mm256_store_si256(reinterpret_cast<__m256i*>(word[g]), word_v[g]);
    }
    for (int lane = 0; lane < kLanes; ++lane) {
      steps[lane] -= run;
      if (steps[lane] == 0) live += load(lane) ? 0 : -1;
    }
  }
}
#endif

}  // namespace

namespace {
bool cpuHasAvx2() {
#if defined(__x86_64__)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}
}  // namespace

void UpdateBatch::queueRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key,
                               const Key& to_key) {
  // Long rays would need a window too large to sweep (LiDAR rays reach thousands of cells);
  // walked at once, they also find the bricks their end points were just marked in.
  const auto reach = [&](int a) { return std::abs(std::int64_t{to_key[a]} - from_key[a]); };
  if (!cpuHasAvx2() || from_key.z == to_key.z || reach(0) >= kLaneReach || reach(1) >= kLaneReach ||
      reach(2) >= kLaneReach / 2) {
    markRayFree(from, to, from_key, to_key);
    return;
  }
  queued_.push_back(QueuedRay{from, to, from_key, to_key});
  if (queued_.size() == kQueuedRays) walkQueued();
}

void UpdateBatch::walkQueued(bool wide) {
  if (queued_.empty()) return;
  // queueRayFree queues only what lanes can walk (AVX2, rays leaving their z-layer).
  lane_rays_.clear();
  if (wide)
    for (std::uint32_t i = 0; i < queued_.size(); ++i) lane_rays_.push_back(i);
  const bool windowed = wide && walkInWindow(lane_rays_);
  std::size_t next_lane = 0;
  for (std::uint32_t i = 0; i < queued_.size(); ++i) {
    if (windowed && next_lane < lane_rays_.size() && lane_rays_[next_lane] == i) {
      ++next_lane;
      continue;
    }
    const QueuedRay& q = queued_[i];
    markRayFree(q.from, q.to, q.from_key, q.to_key);
  }
  queued_.clear();
}

bool UpdateBatch::walkInWindow(std::vector<std::uint32_t>& lanes) {
#if defined(__x86_64__)
  // At most 2^14 bricks (8 MiB).
  constexpr int kMaxBits = 14;
  const auto bitsFor = [](std::int64_t extent) {
    int b = 0;
    while ((std::int64_t{1} << b) < extent) ++b;
    return b;
  };
  const auto boundsOf = [&](Key& lo, Key& hi) {
    lo = hi = brickOf(queued_[lanes.front()].from_key);
    for (const std::uint32_t i : lanes)
      for (const Key& k : {queued_[i].from_key, queued_[i].to_key}) {
        const Key b = brickOf(k);
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b[a]), hi[a] = std::max(hi[a], b[a]);
      }
  };
  Key lo, hi;
  boundsOf(lo, hi);
  Window w{lo, {0, 0, 0}};
  const auto fit = [&] {
    int total = 0;
    for (int a = 0; a < 3; ++a) total += w.bits[a] = bitsFor(std::int64_t{hi[a]} - lo[a] + 1);
    return total <= kMaxBits;
  };
  if (!fit()) {
    // Rays from scattered starts (queued rays are short): keep those within 32 x 32 x 16 bricks
    // around where the first one starts, if that is most of them.
    const std::size_t all = lanes.size();
    const Key c = brickOf(queued_[lanes.front()].from_key);
    const Key box_lo{c.x - 16, c.y - 16, c.z - 8}, box_hi{c.x + 15, c.y + 15, c.z + 7};
    const auto inside = [&](const Key& k) {
      const Key b = brickOf(k);
      for (int a = 0; a < 3; ++a)
        if (b[a] < box_lo[a] || b[a] > box_hi[a]) return false;
      return true;
    };
    const auto outside = [&](std::uint32_t i) { return !inside(queued_[i].from_key) || !inside(queued_[i].to_key); };
    lanes.erase(std::remove_if(lanes.begin(), lanes.end(), outside), lanes.end());
    if (lanes.size() * 2 < all) return false;
    boundsOf(lo, hi);
    w.origin = lo;
    if (!fit()) return false;
  }
  // One scratch brick in front of the window for lanes without a ray; all zero between walks,
  // as are the touched flags.
  const std::size_t words = (w.bricks() + 1) * kBrickWords;
  if (window_.size() < words) window_.resize(words, 0);
  if (touched_.size() < w.bricks() + 1) touched_.resize(w.bricks() + 1, 0);
  std::uint64_t* window = window_.data() + kBrickWords;
  std::uint8_t* touched = touched_.data() + 1;
  walkLanes(queued_, lanes, w, window, touched);
  std::fill_n(window_.data(), kBrickWords, 0);
  touched[-1] = 0;
  const std::size_t mask0 = (std::size_t{1} << w.bits[0]) - 1, mask1 = (std::size_t{1} << w.bits[1]) - 1;
  for (std::size_t b = 0; b < w.bricks(); ++b) {
    if (touched[b] == 0) continue;
    touched[b] = 0;
    std::uint64_t* brick_words = window + b * kBrickWords;
    const Key brick{w.origin.x + static_cast<std::int32_t>(b & mask0),
                    w.origin.y + static_cast<std::int32_t>((b >> w.bits[0]) & mask1),
                    w.origin.z + static_cast<std::int32_t>(b >> (w.bits[0] + w.bits[1]))};
    std::array<std::uint64_t, kBrickWords>& free = brickFor(brickOrigin(brick)).free;
    for (int i = 0; i < kBrickWords; ++i) {
      free[static_cast<std::size_t>(i)] |= brick_words[i];
      brick_words[i] = 0;
    }
  }
  return true;
#else
  (void)lanes;
  return false;
#endif
}

void UpdateBatch::finalize() {
  walkQueued();
  // Sorted by a radix sort of the codes, computed from the packed keys kept beside the bricks:
  // reading the bricks (1 KiB apart) missed the cache on most of a comparison sort's comparisons.
  std::vector<std::pair<std::uint64_t, std::uint32_t>>& order = order_scratch_;
  order.clear();
  for (std::uint32_t slot = 0; slot < packed_keys_.size(); ++slot)
    order.emplace_back(mortonCode(unpackKey(packed_keys_[slot])), slot);
  detail::radixSortByKey(order);
  sorted_.clear();
  sorted_keys_.clear();
  sorted_codes_.clear();
  for (const auto& [code, slot] : order) {
    BrickUpdates& b = brickAt(slot);
    if (b.any_occupied)
      for (std::size_t w = 0; w < kBrickWords; ++w) b.free[w] &= ~b.occupied[w];
    sorted_.push_back(&b);
    sorted_keys_.push_back(unpackKey(packed_keys_[slot]));
    sorted_codes_.push_back(code);
  }
}

void PlanarBatch::reset(const Key& lo, const Key& hi) {
  bx0_ = lo.x >> kBrickBits;
  by0_ = lo.y >> kBrickBits;
  width_ = (hi.x >> kBrickBits) - bx0_ + 1;
  tiles_.assign(tilesFor(lo, hi), Tile{});
  columns_.assign(tiles_.size(), ColumnTile{});
}

void PlanarBatch::finalize() {
  for (std::size_t t = 0; t < columns_.size(); ++t) {
    std::array<std::uint64_t, kLayerWords>& marks = columns_[t].free;
    if ((marks[0] | marks[1] | marks[2] | marks[3]) == 0) continue;
    // A 16 x 16 bit transpose by swapping the off-diagonal blocks of 8, 4, 2 and 1 rows (of
    // 16 bits, four to a word: rows 8 and 4 apart are in other words, 2 and 1 apart in the same).
    std::uint64_t w[kLayerWords] = {marks[0], marks[1], marks[2], marks[3]};
    const auto acrossWords = [](std::uint64_t& a, std::uint64_t& b, int j, std::uint64_t low) {
      const std::uint64_t swap = ((a >> j) ^ b) & low;
      a ^= swap << j;
      b ^= swap;
    };
    acrossWords(w[0], w[2], 8, 0x00FF00FF00FF00FFull);
    acrossWords(w[1], w[3], 8, 0x00FF00FF00FF00FFull);
    acrossWords(w[0], w[1], 4, 0x0F0F0F0F0F0F0F0Full);
    acrossWords(w[2], w[3], 4, 0x0F0F0F0F0F0F0F0Full);
    for (std::uint64_t& word : w) {
      // Rows 2 apart: lanes 0, 1 with lanes 2, 3; then rows 1 apart: lanes 0, 2 with lanes 1, 3.
      std::uint64_t swap = ((word >> 2) ^ (word >> 32)) & 0x0000000033333333ull;
      word ^= (swap << 2) | (swap << 32);
      swap = ((word >> 1) ^ (word >> 16)) & 0x0000555500005555ull;
      word ^= (swap << 1) | (swap << 16);
    }
    for (std::size_t i = 0; i < kLayerWords; ++i) tiles_[t].free[i] |= w[i];
    marks.fill(0);
  }
}

namespace {

// Marks a walk's runs in a planar batch's tiles, moving from tile to tile by pointer steps:
// along the major axis a run is a mask in one row of a Tile (kRows) or of a ColumnTile.
template <bool kRows, int kMajorDir, int kMinorDir>
struct RunMarker {
  using Tile = std::conditional_t<kRows, PlanarBatch::Tile, PlanarBatch::ColumnTile>;
  Tile* tile;
  std::ptrdiff_t tile_step[2];  // to the next tile along the major and the minor axis
  int local[2];                 // the current cell in its tile, major and minor axis
  // `len` + 1 cells from the current one on along the major axis; ends on the last of them.
  void run(int len) {
    constexpr int m = kBrickSize - 1;
    for (;;) {
      // Cells left in this tile after the current one, in the direction of the run.
      const int room = kMajorDir > 0 ? m - local[0] : local[0];
      const int n = std::min(len, room);
      const int first = kMajorDir > 0 ? local[0] : local[0] - n;
      const unsigned cells = ((2u << n) - 1) << first;
      tile->free[static_cast<std::size_t>(local[1] >> 2)] |= std::uint64_t{cells} << ((local[1] & 3) * kBrickSize);
      local[0] += kMajorDir * n;
      len -= n;
      if (len == 0) return;
      // On into the next tile.
      tile += tile_step[0];
      local[0] = kMajorDir > 0 ? 0 : m;
      --len;
    }
  }
  void stepMinor() {
    local[1] += kMinorDir;
    if (local[1] & ~(kBrickSize - 1)) {
      local[1] &= kBrickSize - 1;
      tile += tile_step[1];
    }
  }
};

template <bool kRows, int kMajorDir, int kMinorDir>
void markRuns(const PlanarSegment& seg, typename RunMarker<kRows, kMajorDir, kMinorDir>::Tile* tile,
              std::ptrdiff_t width, const Key& from_key, std::int64_t skip_runs) {
  constexpr int m = kBrickSize - 1;
  const std::int64_t major_n = kRows ? seg.nx : seg.ny, minor_n = kRows ? seg.ny : seg.nx;
  const std::ptrdiff_t step_x = seg.sx, step_y = seg.sy * width;
  const int major_key = kRows ? from_key.x : from_key.y, minor_key = kRows ? from_key.y : from_key.x;
  if (minor_n == 0) {
    RunMarker<kRows, kMajorDir, kMinorDir> marker{
        tile, {kRows ? step_x : step_y, kRows ? step_y : step_x}, {major_key & m, minor_key & m}};
    if (major_n > 0) marker.run(static_cast<int>(major_n - 1));
    return;
  }
  // Run r ends at the count of major boundaries crossed before minor boundary r + 1, from the
  // exact crossing times: floor(((r + 1) one major_d + major_0 minor_d - minor_0 major_d - t) / (one minor_d)),
  // t = 0 for rows and 1 for columns (a tie goes to x: it ends a row and begins a column).
  const std::int64_t one = std::int64_t{1} << seg.shift;
  const std::int64_t major_d = kRows ? seg.dx : seg.dy, minor_d = kRows ? seg.dy : seg.dx;
  const std::int64_t major_0 = kRows ? seg.x0 : seg.y0, minor_0 = kRows ? seg.y0 : seg.x0;
  const std::int64_t den = one * minor_d, add = one * major_d;
  const std::int64_t num = add + major_0 * minor_d - minor_0 * major_d - (kRows ? 0 : 1);
  const std::int64_t add_q = add / den, add_r = add % den;
  // Start at run `skip`: its first cell is where run skip - 1 ended (a product of up to
  // 2^62 by the run count needs 128 bits).
  const std::int64_t skip = std::min(skip_runs, minor_n);
  std::int64_t start = 0, q = num / den, rem = num % den;
  if (skip > 0) {
    __extension__ using Wide = __int128;
    start = std::min(static_cast<std::int64_t>((Wide{num} + Wide{add} * (skip - 1)) / den), major_n);
    const Wide at_skip = Wide{num} + Wide{add} * skip;
    q = static_cast<std::int64_t>(at_skip / den);
    rem = static_cast<std::int64_t>(at_skip % den);
  }
  const int major_cell = major_key + kMajorDir * static_cast<int>(start);
  const int minor_cell = minor_key + kMinorDir * static_cast<int>(skip);
  const std::ptrdiff_t tiles_major = (major_cell >> kBrickBits) - (major_key >> kBrickBits);
  const std::ptrdiff_t tiles_minor = (minor_cell >> kBrickBits) - (minor_key >> kBrickBits);
  RunMarker<kRows, kMajorDir, kMinorDir> marker{
      tile + (kRows ? tiles_major + tiles_minor * width : tiles_minor + tiles_major * width),
      {kRows ? step_x : step_y, kRows ? step_y : step_x},
      {major_cell & m, minor_cell & m}};
  for (std::int64_t r = skip; r < minor_n; ++r) {
    const std::int64_t end = std::min(q, major_n);
    marker.run(static_cast<int>(end - start));
    marker.stepMinor();
    start = end;
    // Without a branch: the carry comes as irregularly as a line's steps.
    rem += add_r;
    const std::int64_t carry = rem >= den;
    rem -= den & -carry;
    q += add_q + carry;
  }
  if (start < major_n) marker.run(static_cast<int>(major_n - 1 - start));
}

}  // namespace

void fanSkipRuns(PlanarBeam* beams, std::size_t count) {
  // A beam's geometry in cells, unmirrored, from the rounded start point.
  struct Ray {
    double dx, dy, length, inverse_length;
  };
  thread_local std::vector<Ray> rays;
  rays.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const PlanarSegment& s = beams[i].seg;
    const double cell = 1.0 / static_cast<double>(std::int64_t{1} << s.shift);
    const double dx = static_cast<double>(s.sx * s.dx) * cell, dy = static_cast<double>(s.sy * s.dy) * cell;
    const double length = std::sqrt(dx * dx + dy * dy);
    rays[i] = Ray{dx, dy, length, length > 0.0 ? 1.0 / length : 0.0};
    beams[i].skip_runs = 0;
  }
  const auto sameStart = [](const PlanarSegment& a, const PlanarSegment& b) {
    const std::int64_t one = std::int64_t{1} << a.shift;
    const auto ux = [one](const PlanarSegment& s) { return s.sx > 0 ? s.x0 : one - 1 - s.x0; };
    const auto uy = [one](const PlanarSegment& s) { return s.sy > 0 ? s.y0 : one - 1 - s.y0; };
    return a.shift == b.shift && ux(a) == ux(b) && uy(a) == uy(b);
  };
  constexpr double kDiagonal = 1.4142135623730951;
  for (std::size_t i = 1; i < count; ++i) {
    PlanarBeam& beam = beams[i];
    const std::size_t step = i & (~i + 1);  // beams i -/+ step: fewer trailing zero bits than i
    if (!beam.traced || i + step >= count) continue;
    const PlanarBeam &left = beams[i - step], &right = beams[i + step];
    const Ray &a = rays[i - step], &b = rays[i + step], &c = rays[i];
    if (!left.traced || !right.traced || !(a.length > 2.0 && b.length > 2.0 && c.length > 0.0)) continue;
    if (!sameStart(beam.seg, left.seg) || !sameStart(beam.seg, right.seg)) continue;
    // Beam strictly between its neighbours, which are less than half a turn apart: sines of
    // one sign, each well beyond its rounding.
    const auto cross = [](const Ray& u, const Ray& v) { return u.dx * v.dy - u.dy * v.dx; };
    const double ab = cross(a, b), ac = cross(a, c), cb = cross(c, b);
    constexpr double sure = 1e-9;
    const double ab_sure = sure * a.length * b.length, ac_sure = sure * a.length * c.length,
                 cb_sure = sure * c.length * b.length;
    const bool counter_clockwise = ab > ab_sure && ac > ac_sure && cb > cb_sure;
    const bool clockwise = ab < -ab_sure && ac < -ac_sure && cb < -cb_sure;
    if (!counter_clockwise && !clockwise) continue;
    // A unit cell inside the wedge of angle t holds a disc of radius 1/2 whose centre is at
    // least 1 / (2 sin(t/2)) from the apex; a cell nearer crosses a side, inside that side's
    // segment if the segment reaches 2 cells further (its end cell is not free).
    const double cos_t = (a.dx * b.dx + a.dy * b.dy) * a.inverse_length * b.inverse_length;
    const double sin_half = std::sqrt(std::max(1.0 - cos_t, 0.0) / 2.0);
    const double radius = std::min({0.999 / (2.0 * sin_half), a.length - 2.0, b.length - 2.0});
    // The cells of runs before r lie within r / |minor extent| of the beam's length, plus a diagonal.
    const bool rows = beam.seg.nx >= beam.seg.ny;
    const double minor = std::abs(rows ? c.dy : c.dx);
    if (!(radius > kDiagonal)) continue;
    const double runs = std::floor((radius - kDiagonal) * minor * c.inverse_length);
    beam.skip_runs = std::min(static_cast<std::int64_t>(runs), rows ? beam.seg.ny : beam.seg.nx);
  }
}

void PlanarBatch::markRayFree(const PlanarSegment& seg, const Key& from_key, std::int64_t skip_runs) {
  // walkPlanar's cells as runs: along the axis that steps more, the walk's cells in each row
  // (or column) of the other are one run, whose end follows from the exact crossing times by
  // an integer division carried from run to run (as in run-slice line drawing).
  if (seg.nx + seg.ny == 0) return;
  const std::size_t at = tileIndex(from_key.x, from_key.y);
  Tile* tile = &tiles_[at];
  ColumnTile* column = &columns_[at];
  // One loop per orientation and direction: the directions are constants in the loop.
  const int major_s = seg.nx >= seg.ny ? seg.sx : seg.sy, minor_s = seg.nx >= seg.ny ? seg.sy : seg.sx;
  const int variant = (seg.nx >= seg.ny ? 4 : 0) + (major_s > 0 ? 2 : 0) + (minor_s > 0 ? 1 : 0);
  switch (variant) {
    case 0: markRuns<false, -1, -1>(seg, column, width_, from_key, skip_runs); break;
    case 1: markRuns<false, -1, 1>(seg, column, width_, from_key, skip_runs); break;
    case 2: markRuns<false, 1, -1>(seg, column, width_, from_key, skip_runs); break;
    case 3: markRuns<false, 1, 1>(seg, column, width_, from_key, skip_runs); break;
    case 4: markRuns<true, -1, -1>(seg, tile, width_, from_key, skip_runs); break;
    case 5: markRuns<true, -1, 1>(seg, tile, width_, from_key, skip_runs); break;
    case 6: markRuns<true, 1, -1>(seg, tile, width_, from_key, skip_runs); break;
    default: markRuns<true, 1, 1>(seg, tile, width_, from_key, skip_runs); break;
  }
}

}  // namespace rtog
