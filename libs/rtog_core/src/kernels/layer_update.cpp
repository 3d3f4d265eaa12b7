#include "kernels/layer_update.hpp"

#include <algorithm>

#include "kernels/cpu.hpp"
#include "storage/brick.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define RTOG_AVX2_DISPATCH 1
#endif

namespace rtog {
namespace detail {
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
                                                             const float deltas[4], LayerCounts& counts) {
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
                 const float deltas[4], LayerCounts& counts) {
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

}  // namespace

std::array<UpdateLayerFn, 2> layerUpdateKernels() {
#if defined(RTOG_AVX2_DISPATCH)
  if (cpuHasAvx2()) return {updateLayer, updateLayerAvx2};
#endif
  return {updateLayer, nullptr};
}

UpdateLayerFn bestLayerUpdate() {
  static const UpdateLayerFn best = [] {
    const auto kernels = layerUpdateKernels();
    return kernels[1] ? kernels[1] : kernels[0];
  }();
  return best;
}


}  // namespace detail
}  // namespace rtog
