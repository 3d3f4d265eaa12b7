#include "kernels/lane_walk.hpp"

#include <algorithm>
#include <limits>

#include "kernels/cpu.hpp"
#include "rtog/core/ray_traversal.hpp"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define RTOG_LANE_WALK 1
#endif

namespace rtog {
namespace detail {

#if defined(RTOG_LANE_WALK)
namespace {

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

void setUpLane(const QueuedRay& q, const LaneWindow& w, LaneRay& r) {
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
__attribute__((target("avx2"))) void walkLanesAvx2(const std::vector<QueuedRay>& queued,
                                               const std::vector<std::uint32_t>& rays, const LaneWindow& w,
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

}  // namespace
#endif

bool laneWalkAvailable() {
#if defined(RTOG_LANE_WALK)
  return cpuHasAvx2();
#else
  return false;
#endif
}

void walkLanes(const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays, const LaneWindow& w,
               std::uint64_t* window, std::uint8_t* touched) {
#if defined(RTOG_LANE_WALK)
  walkLanesAvx2(queued, rays, w, window, touched);
#else
  (void)queued, (void)rays, (void)w, (void)window, (void)touched;
#endif
}

}  // namespace detail
}  // namespace rtog
