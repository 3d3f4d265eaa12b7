#include "kernels/lane_walk.hpp"

#include <algorithm>
#include <cstdlib>
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

// Compiled for AVX2, and called only from the kernels below: called between steps with the upper
// halves of the vector registers in use, legacy-SSE code pays on Intel cores for every
// instruction (a false dependency and a merge), where VEX-encoded code pays nothing.
__attribute__((target("avx2"))) std::int64_t setUpLane(const QueuedRay& q, const LaneWindow& w, double t[3],
                                                       double dt[3], std::int64_t left[3], std::int64_t delta[3],
                                                       std::int64_t& index) {
  int step[3];
  const std::int64_t steps = detail::setUpWalk(q.from, q.to, q.from_key, q.to_key, step, t, dt);
  for (int a = 0; a < 3; ++a) {
    const std::int64_t diff = std::int64_t{q.to_key[a]} - q.from_key[a];
    left[a] = diff < 0 ? -diff : diff;
    delta[a] = std::int64_t{step[a]} * (std::int64_t{1} << w.shift(a));
  }
  index = kBrickWords * 64 + w.cellIndex(q.from_key);  // past the scratch words
  return steps;
}

// The lanes walk rays in waves: a wave of rays set up at once is walked to its longest ray's
// end, each lane marking its own ray's cells, then the scratch cell. Rays queued side by side
// come from neighbouring pixels or beams and have about the same length, so little of a wave
// is spent waiting; lanes that each took a new ray when theirs ended stopped every few steps
// instead, to store, refill and reload their state.
//
// A wave's state for the AVX2 kernel, walkRay's floating-point form (its 3D branch): kGroups
// registers of kWidth lanes for each quantity. Inlined into the kernel whole, so that it is
// compiled for the kernel's instruction set (an out-of-line copy would be legacy SSE, called
// with the vector registers' upper halves in use).
template <int kGroups, int kWidth>
struct Wave {
  static constexpr int kLanes = kGroups * kWidth;
  alignas(64) double t[kGroups][3][kWidth], dt[kGroups][3][kWidth];
  alignas(64) std::int64_t left[kGroups][3][kWidth];   // steps left along each axis
  alignas(64) std::int64_t delta[kGroups][3][kWidth];  // what a step along each axis adds to the index
  alignas(64) std::int64_t index[kGroups][kWidth];     // the current cell's index in the window
  alignas(64) std::int64_t steps[kGroups][kWidth];     // the cells the lane marks
  /// Loads rays[first, first + kLanes) into the lanes; returns the most steps of them. A
  /// lane past the end has no steps, on cell 0, in the window's scratch words.
  __attribute__((always_inline)) std::int64_t load(const std::vector<QueuedRay>& queued,
                                                   const std::vector<std::uint32_t>& rays, std::size_t first,
                                                   const LaneWindow& w) {
    std::int64_t most = 0;
    for (int lane = 0; lane < kLanes; ++lane) {
      const int g = lane / kWidth, j = lane % kWidth;
      if (first + lane < rays.size()) {
        double rt[3], rdt[3];
        std::int64_t rleft[3], rdelta[3];
        steps[g][j] = setUpLane(queued[rays[first + lane]], w, rt, rdt, rleft, rdelta, index[g][j]);
        most = std::max(most, steps[g][j]);
        for (int a = 0; a < 3; ++a) {
          t[g][a][j] = rt[a];
          dt[g][a][j] = rdt[a];
          left[g][a][j] = rleft[a];
          delta[g][a][j] = rdelta[a];
        }
      } else {
        for (int a = 0; a < 3; ++a) t[g][a][j] = dt[g][a][j] = 0.0, left[g][a][j] = -1, delta[g][a][j] = 0;
        index[g][j] = steps[g][j] = 0;
      }
    }
    return most;
  }
};

// Eight rays in two groups of four AVX2 lanes: each step is branch-free (the axis by compares
// and blends, the cell by one add of the chosen axis's stride), so the two groups' dependency
// chains overlap instead of waiting on mispredicted branches. `touched` gets a non-zero byte for
// each run of kBrickWords words marked (index: word / kBrickWords), so that only those are swept.
__attribute__((target("avx2"))) void walkLanesAvx2(const std::vector<QueuedRay>& queued,
                                               const std::vector<std::uint32_t>& rays, const LaneWindow& w,
                                               std::uint64_t* window, std::uint8_t* touched) {
  constexpr int kGroups = 2, kWidth = 4;
  Wave<kGroups, kWidth> L;
  std::uint64_t* const words = window - kBrickWords;  // the scratch words first
  std::uint8_t* const runs = touched - 1;
  const __m256d inf = _mm256_set1_pd(kInf);
  const __m256i zero = _mm256_setzero_si256(), one = _mm256_set1_epi64x(1), low6 = _mm256_set1_epi64x(63),
                all = _mm256_set1_epi64x(-1);
  for (std::size_t first = 0; first < rays.size(); first += L.kLanes) {
    const std::int64_t most = L.load(queued, rays, first, w);
    __m256d T[kGroups][3];
    __m256i left_v[kGroups][3], index_v[kGroups], steps_v[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      for (int a = 0; a < 3; ++a) {
        T[g][a] = _mm256_load_pd(L.t[g][a]);
        left_v[g][a] = _mm256_load_si256(reinterpret_cast<const __m256i*>(L.left[g][a]));
      }
      index_v[g] = _mm256_load_si256(reinterpret_cast<const __m256i*>(L.index[g]));
      steps_v[g] = _mm256_load_si256(reinterpret_cast<const __m256i*>(L.steps[g]));
    }
    __m256i step_v = zero;
    for (std::int64_t step = 0; step < most; ++step, step_v = _mm256_add_epi64(step_v, one))
      for (int g = 0; g < kGroups; ++g) {
        // A lane past its ray's end marks cell 0, in the scratch words.
        const __m256i cell = _mm256_and_si256(index_v[g], _mm256_cmpgt_epi64(steps_v[g], step_v));
        const __m256i at = _mm256_srli_epi64(cell, 6);
        const __m256i bit = _mm256_sllv_epi64(one, _mm256_and_si256(cell, low6));
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
              _mm256_blendv_pd(_mm256_add_pd(T[g][a], _mm256_load_pd(L.dt[g][a])), inf, at_end);
          T[g][a] = _mm256_blendv_pd(T[g][a], next_t, chosen[a]);
          index_v[g] = _mm256_add_epi64(
              index_v[g],
              _mm256_and_si256(_mm256_load_si256(reinterpret_cast<const __m256i*>(L.delta[g][a])), step_mask));
        }
      }
  }
}

// Sets up eight lanes as setUpLane does, from rays[first, first + 8) (lanes past the end get
// none: no steps). The same IEEE operations on the same operands, eight at a time: the rays'
// ends and keys are gathered, the divisions masked where an axis does not move.
__attribute__((target("avx512f"), always_inline)) inline void setUpLanes8(
    const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays, std::size_t first,
    const LaneWindow& w, __m512d T[3], __m512d DT[3], __m512i left[3], __m512i delta[3], __m512i& index,
    __m512i& steps) {
  const std::size_t n = first < rays.size() ? std::min<std::size_t>(8, rays.size() - first) : 0;
  const auto live = static_cast<__mmask8>((1u << n) - 1u);
  alignas(64) std::int64_t offsets[8] = {};
  for (std::size_t j = 0; j < n; ++j) offsets[j] = std::int64_t{rays[first + j]} * std::int64_t{sizeof(QueuedRay)};
  const __m512i at = _mm512_load_si512(offsets);
  const QueuedRay& q0 = queued.front();
  const auto field = [](const double* p) { return static_cast<const void*>(p); };
  const auto coordinate = [](const Key& k, int a) {
    return static_cast<const void*>(a == 0 ? &k.x : a == 1 ? &k.y : &k.z);
  };
  const __m512d inf = _mm512_set1_pd(kInf), plus = _mm512_set1_pd(1.0), minus = _mm512_set1_pd(-1.0);
  const __m512i zero = _mm512_setzero_si512();
  constexpr __mmask8 kAll = 0xFF;
  steps = zero;
  index = zero;
  for (int a = 0; a < 3; ++a) {
    const __m512d from = _mm512_mask_i64gather_pd(_mm512_setzero_pd(), live, at, field(&q0.from[a]), 1);
    const __m512d to = _mm512_mask_i64gather_pd(_mm512_setzero_pd(), live, at, field(&q0.to[a]), 1);
    const __m256i none = _mm256_setzero_si256();
    const __m256i from_key32 = _mm512_mask_i64gather_epi32(none, live, at, coordinate(q0.from_key, a), 1);
    const __m256i to_key32 = _mm512_mask_i64gather_epi32(none, live, at, coordinate(q0.to_key, a), 1);
    const __m512i from_key = _mm512_maskz_cvtepi32_epi64(kAll, from_key32);
    const __m512i diff = _mm512_maskz_sub_epi64(kAll, _mm512_maskz_cvtepi32_epi64(kAll, to_key32), from_key);
    const __mmask8 up = _mm512_cmpgt_epi64_mask(diff, zero), down = _mm512_cmplt_epi64_mask(diff, zero);
    left[a] = _mm512_maskz_abs_epi64(kAll, diff);
    steps = _mm512_maskz_add_epi64(kAll, steps, left[a]);
    const __m512d d = _mm512_maskz_sub_pd(kAll, to, from);
    const __m512d key = _mm512_maskz_cvtepi32_pd(kAll, from_key32);
    const __m512d boundary = _mm512_mask_add_pd(key, up, key, plus);
    const auto moves = static_cast<__mmask8>(up | down);
    DT[a] = _mm512_mask_div_pd(inf, moves, _mm512_mask_mov_pd(plus, down, minus), d);
    T[a] = _mm512_mask_div_pd(inf, moves, _mm512_maskz_sub_pd(kAll, boundary, from), d);
    const __m512i stride = _mm512_set1_epi64(std::int64_t{1} << w.shift(a));
    delta[a] = _mm512_mask_sub_epi64(_mm512_maskz_mov_epi64(up, stride), down, zero, stride);
    const __m512i window_start = _mm512_set1_epi64(std::int64_t{w.origin[a]} * kBrickSize);
    const __m512i local = _mm512_maskz_sub_epi64(kAll, from_key, window_start);
    index = _mm512_maskz_or_epi64(kAll, index, _mm512_maskz_sllv_epi64(kAll, local, _mm512_set1_epi64(w.shift(a))));
  }
  // Past the scratch words, as setUpLane.
  index = _mm512_maskz_add_epi64(kAll, index, _mm512_set1_epi64(std::int64_t{kBrickWords} * 64));
}

// One wave of the AVX-512 walk (below), from its lanes' set-up to its longest ray's end. With
// kShared (rays of neighbouring pixels side by side) a lane in the same cell as its left
// neighbour marks nothing, the other lanes' marks compressed to the front, the first two taken
// from the registers; else every lane marks, through memory.
template <bool kShared>
__attribute__((target("avx512f"), always_inline)) inline void walkWave512(
    __m512d (&T)[2][3], const __m512d (&DT)[2][3], __m512i (&left_v)[2][3], const __m512i (&delta_v)[2][3],
    __m512i (&index_v)[2], const __m512i (&steps_v)[2], std::int64_t most, std::uint64_t* words, std::uint8_t* runs) {
  constexpr int kGroups = 2, kWidth = 8;
  constexpr __mmask8 kAll = 0xFF;  // the maskz forms: the unmasked ones read an undefined register
  alignas(64) std::int64_t at_s[kWidth];
  alignas(64) std::uint64_t bit_s[kWidth];
  const __m512d inf = _mm512_set1_pd(kInf);
  const __m512i zero = _mm512_setzero_si512(), one = _mm512_set1_epi64(1), low6 = _mm512_set1_epi64(63);
  __m512i step_v = zero;
  for (std::int64_t step = 0; step < most; ++step, step_v = _mm512_maskz_add_epi64(kAll, step_v, one))
#pragma GCC unroll 2
    for (int g = 0; g < kGroups; ++g) {
      // A lane past its ray's end marks cell 0, in the scratch words.
      const __m512i all_cells = _mm512_maskz_mov_epi64(_mm512_cmpgt_epi64_mask(steps_v[g], step_v), index_v[g]);
      if (kShared) {
        const auto own = static_cast<__mmask8>(
            _mm512_cmpneq_epi64_mask(all_cells, _mm512_maskz_alignr_epi64(kAll, all_cells, all_cells, 7)) | 1u);
        const __m512i cell = _mm512_maskz_compress_epi64(own, all_cells);
        const __m512i at = _mm512_maskz_srli_epi64(kAll, cell, 6);
        const __m512i bit = _mm512_maskz_sllv_epi64(kAll, one, _mm512_and_si512(cell, low6));
        // The first two marks always (the compress leaves cell 0 behind the lanes it keeps), so
        // that the count's branch goes the same way step after step.
        const __m128i at01 = _mm512_maskz_extracti32x4_epi32(0xF, at, 0);
        const __m128i bit01 = _mm512_maskz_extracti32x4_epi32(0xF, bit, 0);
        const std::int64_t at0 = _mm_cvtsi128_si64(at01), at1 = _mm_extract_epi64(at01, 1);
        words[at0] |= static_cast<std::uint64_t>(_mm_cvtsi128_si64(bit01));
        words[at1] |= static_cast<std::uint64_t>(_mm_extract_epi64(bit01, 1));
        runs[at0 >> 6] = runs[at1 >> 6] = 1;
        const int marks = __builtin_popcount(own);
        if (marks > 2) {
          _mm512_store_si512(at_s, at);
          _mm512_store_si512(bit_s, bit);
          for (int j = 2; j < marks; ++j) {
            words[at_s[j]] |= bit_s[j];
            runs[at_s[j] >> 6] = 1;
          }
        }
      } else {
        _mm512_store_si512(at_s, _mm512_maskz_srli_epi64(kAll, all_cells, 6));
        _mm512_store_si512(bit_s, _mm512_maskz_sllv_epi64(kAll, one, _mm512_and_si512(all_cells, low6)));
        for (int j = 0; j < kWidth; ++j) {
          words[at_s[j]] |= bit_s[j];
          runs[at_s[j] >> 6] = 1;
        }
      }
      // walkRay's choice: x if tx <= ty and tx <= tz, else y if ty <= tz, else z.
      const __mmask8 x_first =
          _mm512_cmp_pd_mask(T[g][0], T[g][1], _CMP_LE_OQ) & _mm512_cmp_pd_mask(T[g][0], T[g][2], _CMP_LE_OQ);
      const auto y_first = static_cast<__mmask8>(~x_first & _mm512_cmp_pd_mask(T[g][1], T[g][2], _CMP_LE_OQ));
      const auto z_first = static_cast<__mmask8>(~(x_first | y_first));
      const __mmask8 chosen[3] = {x_first, y_first, z_first};
      for (int a = 0; a < 3; ++a) {
        const __mmask8 k = chosen[a];
        left_v[g][a] = _mm512_mask_sub_epi64(left_v[g][a], k, left_v[g][a], one);
        const __mmask8 at_end = _mm512_mask_cmpeq_epi64_mask(k, left_v[g][a], zero);
        T[g][a] = _mm512_mask_add_pd(T[g][a], k, T[g][a], DT[g][a]);
        T[g][a] = _mm512_mask_mov_pd(T[g][a], at_end, inf);
        index_v[g] = _mm512_mask_add_epi64(index_v[g], k, index_v[g], delta_v[g][a]);
      }
    }
}

// The same walk, sixteen rays in two groups of eight AVX-512 lanes: the axis choice and the
// per-axis updates are masked operations where AVX2 needs blends.
__attribute__((target("avx512f"))) void walkLanesAvx512(const std::vector<QueuedRay>& queued,
                                                    const std::vector<std::uint32_t>& rays,
                                                    const std::vector<std::uint8_t>& shared, const LaneWindow& w,
                                                    std::uint64_t* window, std::uint8_t* touched) {
  constexpr int kGroups = 2, kWidth = 8;
  constexpr __mmask8 kAll = 0xFF;
  std::uint64_t* const words = window - kBrickWords;
  std::uint8_t* const runs = touched - 1;
  for (std::size_t first = 0; first < rays.size(); first += kGroups * kWidth) {
    __m512d T[kGroups][3], DT[kGroups][3];
    __m512i left_v[kGroups][3], delta_v[kGroups][3], index_v[kGroups], steps_v[kGroups];
    for (int g = 0; g < kGroups; ++g)
      setUpLanes8(queued, rays, first + g * kWidth, w, T[g], DT[g], left_v[g], delta_v[g], index_v[g], steps_v[g]);
    alignas(64) std::int64_t longest[kWidth];  // (GCC's reduce_max reads an undefined register)
    _mm512_store_si512(longest, _mm512_maskz_max_epi64(kAll, steps_v[0], steps_v[1]));
    const std::int64_t most = *std::max_element(longest, longest + kWidth);
    if (shared[first / kWaveBlock] != 0) {
      walkWave512<true>(T, DT, left_v, delta_v, index_v, steps_v, most, words, runs);
    } else {
      walkWave512<false>(T, DT, left_v, delta_v, index_v, steps_v, most, words, runs);
    }
  }
}

}  // namespace
#endif

LaneKernel laneKernel() {
#if defined(RTOG_LANE_WALK)
  static const LaneKernel best = cpuPrefersAvx512() ? LaneKernel::Avx512
                                 : cpuHasAvx2()     ? LaneKernel::Avx2
                                                    : LaneKernel::None;
  return best;
#else
  return LaneKernel::None;
#endif
}

bool laneKernelRuns(LaneKernel k) {
#if defined(RTOG_LANE_WALK)
  return k == LaneKernel::None || (k == LaneKernel::Avx2 && cpuHasAvx2()) ||
         (k == LaneKernel::Avx512 && cpuHasAvx512());
#else
  return k == LaneKernel::None;
#endif
}

void orderForWaves(const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays,
                   std::vector<std::uint32_t>& order, std::vector<std::uint8_t>& shared) {
  // Blocks of kBlock rays, each kept as queued (neighbouring pixels side by side: the AVX-512
  // lanes skip a neighbour's cell) unless its waves would spend more than an eighth of their
  // steps waiting, as where a LiDAR's rings alternate; such a block is put in order of length,
  // stably, by a counting sort on length / 4.
  constexpr std::size_t kBlock = kWaveBlock, kWave = 16, kKeys = 256;
  std::uint32_t length[kBlock];
  std::uint16_t count[kKeys + 1];
  order.resize(rays.size());
  shared.assign((rays.size() + kBlock - 1) / kBlock, 0);
  for (std::size_t first = 0; first < rays.size(); first += kBlock) {
    const std::size_t n = std::min(kBlock, rays.size() - first);
    std::uint64_t useful = 0, waiting = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const QueuedRay& q = queued[rays[first + j]];
      std::int64_t l = 0;
      for (int a = 0; a < 3; ++a) l += std::abs(std::int64_t{q.to_key[a]} - q.from_key[a]);
      length[j] = static_cast<std::uint32_t>(l);
      useful += length[j];
    }
    for (std::size_t w = 0; w < n; w += kWave) {
      const std::size_t end = std::min(n, w + kWave);
      const std::uint32_t most = *std::max_element(length + w, length + end);
      for (std::size_t j = w; j < end; ++j) waiting += most - length[j];
    }
    if (waiting * 8 <= useful) {
      std::copy(rays.begin() + first, rays.begin() + first + n, order.begin() + first);
      shared[first / kBlock] = 1;
      continue;
    }
    const auto key = [&](std::size_t j) { return std::min<std::size_t>(length[j] >> 1, kKeys - 1); };
    std::fill(count, count + kKeys + 1, 0);
    for (std::size_t j = 0; j < n; ++j) ++count[key(j) + 1];
    for (std::size_t k = 1; k <= kKeys; ++k) count[k] += count[k - 1];
    for (std::size_t j = 0; j < n; ++j) order[first + count[key(j)]++] = rays[first + j];
  }
}

void walkLanes(LaneKernel kernel, const std::vector<QueuedRay>& queued, const std::vector<std::uint32_t>& rays,
               const std::vector<std::uint8_t>& shared, const LaneWindow& w, std::uint64_t* window,
               std::uint8_t* touched) {
#if defined(RTOG_LANE_WALK)
  if (kernel == LaneKernel::Avx512) return walkLanesAvx512(queued, rays, shared, w, window, touched);
  if (kernel == LaneKernel::Avx2) return walkLanesAvx2(queued, rays, w, window, touched);
#endif
  (void)kernel, (void)queued, (void)rays, (void)shared, (void)w, (void)window, (void)touched;
}

}  // namespace detail
}  // namespace rtog
