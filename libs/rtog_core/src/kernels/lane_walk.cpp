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
  std::int64_t left[3];   // steps left along each axis
  std::int64_t delta[3];  // what a step along each axis adds to the cell index
  std::int64_t index;     // the current cell's index in the window
  std::int64_t steps;
};

// Compiled for AVX2 like its caller: called between steps with the upper halves of the YMM
// registers in use, legacy-SSE code pays on Intel cores for every instruction (a false
// dependency and a merge), where VEX-encoded code pays nothing.
__attribute__((target("avx2"))) void setUpLane(const QueuedRay& q, const LaneWindow& w, LaneRay& r) {
  int step[3];
  r.steps = detail::setUpWalk(q.from, q.to, q.from_key, q.to_key, step, r.t, r.dt);
  for (int a = 0; a < 3; ++a) {
    const std::int64_t diff = std::int64_t{q.to_key[a]} - q.from_key[a];
    r.left[a] = diff < 0 ? -diff : diff;
    r.delta[a] = std::int64_t{step[a]} * (std::int64_t{1} << w.shift(a));
  }
  r.index = kBrickWords * 64 + w.cellIndex(q.from_key);  // past the scratch words
}

// Eight rays in two groups of four AVX2 lanes: each step is branch-free (the axis by compares
// and blends, the cell by one add of the chosen axis's stride), so the two groups' dependency
// chains overlap instead of waiting on mispredicted branches. A lane whose ray ends takes the
// next ray. `touched` gets a non-zero byte for each run of kBrickWords words marked (index:
// word / kBrickWords), so that only those are swept.
__attribute__((target("avx2"))) void walkLanesAvx2(const std::vector<QueuedRay>& queued,
                                               const std::vector<std::uint32_t>& rays, const LaneWindow& w,
                                               std::uint64_t* window, std::uint8_t* touched) {
  constexpr int kGroups = 2, kLanes = 4 * kGroups;
  alignas(32) double t[kGroups][3][4], dt[kGroups][3][4];
  alignas(32) std::int64_t left[kGroups][3][4], delta[kGroups][3][4], index[kGroups][4];
  std::int64_t steps[kLanes];
  std::size_t next = 0;
  int live = 0;
  // The window's scratch words come first here: a lane without a ray stands still (no
  // stride, no axis ever at its end) on cell 0, in them.
  std::uint64_t* const words = window - kBrickWords;
  std::uint8_t* const runs = touched - 1;
  const auto load = [&](int lane) {
    const int g = lane / 4, j = lane % 4;
    if (next < rays.size()) {  // queued rays leave their z-layer: at least one step
      LaneRay r;
      setUpLane(queued[rays[next++]], w, r);
      for (int a = 0; a < 3; ++a) {
        t[g][a][j] = r.t[a];
        dt[g][a][j] = r.dt[a];
        left[g][a][j] = r.left[a];
        delta[g][a][j] = r.delta[a];
      }
      index[g][j] = r.index;
      steps[lane] = r.steps;
      return true;
    }
    for (int a = 0; a < 3; ++a) {
      t[g][a][j] = dt[g][a][j] = 0.0;
      left[g][a][j] = -1;
      delta[g][a][j] = 0;
    }
    index[g][j] = 0;
    steps[lane] = std::numeric_limits<std::int64_t>::max();
    return false;
  };
  for (int lane = 0; lane < kLanes; ++lane) live += load(lane);
  const __m256d inf = _mm256_set1_pd(kInf);
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi64x(1), low6 = _mm256_set1_epi64x(63),
                all = _mm256_set1_epi64x(-1);
  while (live > 0) {
    __m256d T[kGroups][3];
    __m256i left_v[kGroups][3], index_v[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      for (int a = 0; a < 3; ++a) {
        T[g][a] = _mm256_load_pd(t[g][a]);
        left_v[g][a] = _mm256_load_si256(reinterpret_cast<const __m256i*>(left[g][a]));
      }
      index_v[g] = _mm256_load_si256(reinterpret_cast<const __m256i*>(index[g]));
    }
    std::int64_t run = steps[0];
    for (int lane = 1; lane < kLanes; ++lane) run = std::min(run, steps[lane]);
    for (std::int64_t step = 0; step < run; ++step)
      for (int g = 0; g < kGroups; ++g) {
        const __m256i at = _mm256_srli_epi64(index_v[g], 6);
        const __m256i bit = _mm256_sllv_epi64(one, _mm256_and_si256(index_v[g], low6));
        const __m128i at_lo = _mm256_castsi256_si128(at), at_hi = _mm256_extracti128_si256(at, 1);
        const __m128i bit_lo = _mm256_castsi256_si128(bit), bit_hi = _mm256_extracti128_si256(bit, 1);
        const std::int64_t at0 = _mm_cvtsi128_si64(at_lo), at1 = _mm_extract_epi64(at_lo, 1),
                           at2 = _mm_cvtsi128_si64(at_hi), at3 = _mm_extract_epi64(at_hi, 1);
        words[at0] |= static_cast<std::uint64_t>(_mm_cvtsi128_si64(bit_lo));
        words[at1] |= static_cast<std::uint64_t>(_mm_extract_epi64(bit_lo, 1));
        words[at2] |= static_cast<std::uint64_t>(_mm_cvtsi128_si64(bit_hi));
        words[at3] |= static_cast<std::uint64_t>(_mm_extract_epi64(bit_hi, 1));
        runs[at0 >> 6] = runs[at1 >> 6] = runs[at2 >> 6] = runs[at3 >> 6] = 1;
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
          index_v[g] = _mm256_add_epi64(
              index_v[g],
              _mm256_and_si256(_mm256_load_si256(reinterpret_cast<const __m256i*>(delta[g][a])), step_mask));
        }
      }
    for (int g = 0; g < kGroups; ++g) {
      for (int a = 0; a < 3; ++a) {
        _mm256_store_pd(t[g][a], T[g][a]);
        _mm256_store_si256(reinterpret_cast<__m256i*>(left[g][a]), left_v[g][a]);
      }
      _mm256_store_si256(reinterpret_cast<__m256i*>(index[g]), index_v[g]);
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
