#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <random>

#include "kernels/layer_update.hpp"
#include "storage/brick.hpp"

using namespace rtog;

// The planar layer update kernels against the rule they implement, cell by cell: occupied marks
// add the hit delta, the other free marks the miss delta, clamped; counts of marked cells and of
// known cells left unchanged. The AVX2 kernel (where the CPU has it) must match bit for bit.
TEST(OccupancyMap, LayerUpdateKernelsFollowTheUpdateRule) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const float deltas[4] = {0.85f, -0.4f, -2.0f, 3.5f};
  const auto kernels = detail::layerUpdateKernels();
  for (int trial = 0; trial < 2000; ++trial) {
    std::array<float, kLayerCells> start{};
    std::array<std::uint64_t, kLayerWords> known{}, occupied{}, free{};
    const double p_occupied = 0.3 * u(rng), p_free = u(rng), p_known = u(rng);
    for (int c = 0; c < kLayerCells; ++c) {
      const double r = u(rng);  // some cells at the clamps, where an update changes nothing
      start[static_cast<std::size_t>(c)] = r < 0.2 ? 3.5f : (r < 0.4 ? -2.0f : static_cast<float>(-2.0 + 5.5 * u(rng)));
      const std::uint64_t bit = std::uint64_t{1} << (c & 63);
      const auto w = static_cast<std::size_t>(c >> 6);
      if (u(rng) < p_known) known[w] |= bit;
      if (u(rng) < p_occupied) occupied[w] |= bit;
      if (u(rng) < p_free) free[w] |= bit;  // overlapping occupied marks too: occupied wins
    }
    std::array<float, kLayerCells> expected = start;
    std::array<std::uint64_t, kLayerWords> expected_known = known;
    detail::LayerCounts expected_counts;
    for (int c = 0; c < kLayerCells; ++c) {
      const auto w = static_cast<std::size_t>(c >> 6);
      const std::uint64_t bit = std::uint64_t{1} << (c & 63);
      const bool o = (occupied[w] & bit) != 0, f = !o && (free[w] & bit) != 0;
      if (!o && !f) continue;
      float& v = expected[static_cast<std::size_t>(c)];
      const float updated = std::min(std::max(v + (o ? deltas[0] : deltas[1]), deltas[2]), deltas[3]);
      expected_counts.unchanged += (known[w] & bit) != 0 && updated == v;
      expected_counts.occupied += o;
      expected_counts.free += f;
      v = updated;
      expected_known[w] |= bit;
    }
    for (const detail::UpdateLayerFn kernel : kernels) {
      if (!kernel) continue;
      std::array<float, kLayerCells> values = start;
      std::array<std::uint64_t, kLayerWords> k = known;
      detail::LayerCounts counts;
      kernel(values.data(), k.data(), occupied.data(), free.data(), deltas, counts);
      ASSERT_EQ(std::memcmp(values.data(), expected.data(), sizeof(values)), 0) << "trial " << trial;
      ASSERT_EQ(k, expected_known);
      ASSERT_EQ(counts.unchanged, expected_counts.unchanged);
      ASSERT_EQ(counts.occupied, expected_counts.occupied);
      ASSERT_EQ(counts.free, expected_counts.free);
    }
  }
  if (!kernels[1]) GTEST_SKIP() << "this CPU has no AVX2: only the portable kernel was checked";
}
