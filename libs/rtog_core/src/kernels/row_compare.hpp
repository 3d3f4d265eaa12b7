// Small SSE2 helpers of the box cover and of spinning waits (SSE2 is in the x86-64 baseline;
// other targets get the portable form).
#pragma once

#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace rtog {
namespace detail {

/// Bit x set where row[x] == v, for the 16 floats of a brick row.
inline std::uint32_t equalMask16(const float* row, float v) {
  std::uint32_t mask = 0;
#if defined(__SSE2__)
  const __m128 vv = _mm_set1_ps(v);
  for (int q = 0; q < 4; ++q)
    mask |= static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(row + 4 * q), vv))) << (4 * q);
#else
  for (int x = 0; x < 16; ++x) mask |= static_cast<std::uint32_t>(row[x] == v) << x;
#endif
  return mask;
}

/// Bit x set where row[x] == v, for the 16 int8 codes of a brick row.
inline std::uint32_t equalMask16(const std::int8_t* row, std::int8_t v) {
#if defined(__SSE2__)
  const __m128i r = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row));
  return static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_cmpeq_epi8(r, _mm_set1_epi8(v))));
#else
  std::uint32_t mask = 0;
  for (int x = 0; x < 16; ++x) mask |= static_cast<std::uint32_t>(row[x] == v) << x;
  return mask;
#endif
}

/// A hint to the CPU inside a spin-wait loop.
inline void cpuRelax() {
#if defined(__SSE2__)
  _mm_pause();
#endif
}

}  // namespace detail
}  // namespace rtog
