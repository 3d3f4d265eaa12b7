#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <vector>

#include "storage/box_cover.hpp"

using namespace rtog;

namespace {

struct CoverBox {
  int lo[3], hi[3];
  float value;
  bool operator==(const CoverBox& o) const {
    return std::equal(lo, lo + 3, o.lo) && std::equal(hi, hi + 3, o.hi) && value == o.value;
  }
};

}  // namespace

// The planar cache covers a brick's single changed layer with its own loop (masks of equal
// cells); it must give the general greedy cover's boxes, in the same order: random layers of
// few distinct values, sparse to full, blocky and noisy, every z, with merging on, off and
// only for some values.
TEST(OccupancyMap, CoverOfOneLayerEqualsTheGeneralCover) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const float palette[] = {-2.0f, -0.4f, 0.4f, 0.85f, 3.5f};
  std::size_t merged = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const int z = trial % kBrickSize, policy = trial % 3, distinct = 1 + trial % 5;
    const double density = 0.2 + 0.8 * u(rng), blockiness = u(rng);
    std::array<float, kLayerCells> values{};
    std::array<std::uint64_t, kLayerWords> known{};
    for (int c = 0; c < kLayerCells; ++c) {
      // Blocky layers copy the cell to the left or below most of the time.
      const bool copy = c > 0 && u(rng) < blockiness;
      const int source = c % kBrickSize > 0 && u(rng) < 0.5 ? c - 1 : std::max(c - kBrickSize, 0);
      values[static_cast<std::size_t>(c)] = copy ? values[static_cast<std::size_t>(source)]
                                                 : palette[static_cast<std::size_t>(static_cast<int>(u(rng) * distinct))];
      if (u(rng) < density) known[static_cast<std::size_t>(c >> 6)] |= std::uint64_t{1} << (c & 63);
    }
    const auto mergeable = [policy](float v) { return policy == 0 || (policy == 1 && v > 0.5f); };
    std::vector<CoverBox> general, layer;
    BrickMask mask{};
    std::copy(known.begin(), known.end(), mask.begin() + z * kLayerWords);
    const auto valueAt = [&](int cell) { return values[static_cast<std::size_t>(cell % kLayerCells)]; };
    detail::coverGreedily(
        mask, [&](int start, int cell) { return valueAt(cell) == valueAt(start) && mergeable(valueAt(start)); },
        [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
          general.push_back(CoverBox{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, valueAt(start)});
        });
    detail::coverLayer(known, values.data(), z, mergeable,
                       [&](const std::uint8_t lo[3], const std::uint8_t hi[3], float v) {
                         layer.push_back(CoverBox{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, v});
                       });
    ASSERT_TRUE(layer == general) << "trial " << trial << ": " << layer.size() << " boxes against " << general.size();
    for (const CoverBox& b : general) merged += b.lo[0] != b.hi[0] || b.lo[1] != b.hi[1];
  }
  EXPECT_GT(merged, 5000u);  // boxes of more than one cell, in both directions, were compared
}


// A brick covered anew from a dense table (insertion's graded bricks) is grown by row masks; it
// must give the general greedy cover's boxes, in the same order: random bricks of few distinct
// values, sparse to full, blocky along x, y and z or noisy, with merging on, off and only for
// some values. Cells outside the known mask hold values too (a reused table's), which must not
// join.
TEST(OccupancyMap, CoverOfADenseBrickEqualsTheGeneralCover) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const float palette[] = {-2.0f, -0.4f, 0.4f, 0.85f, 3.5f};
  std::size_t merged_z = 0, boxes = 0;
  std::vector<float> values(kBrickCells);
  for (int trial = 0; trial < 300; ++trial) {
    const int policy = trial % 3, distinct = 1 + trial % 5;
    const double density = 0.2 + 0.8 * u(rng), blockiness = u(rng);
    BrickMask known{};
    for (int c = 0; c < kBrickCells; ++c) {
      // Blocky bricks copy the cell to the left, below or underneath most of the time.
      const bool copy = c > 0 && u(rng) < blockiness;
      const double pick = u(rng);
      const int source = pick < 0.34 && c % kBrickSize > 0 ? c - 1
                         : pick < 0.67 && c >= kBrickSize ? c - kBrickSize
                                                           : std::max(c - kLayerCells, 0);
      values[static_cast<std::size_t>(c)] = copy ? values[static_cast<std::size_t>(source)]
                                                 : palette[static_cast<std::size_t>(static_cast<int>(u(rng) * distinct))];
      if (u(rng) < density) known[static_cast<std::size_t>(c >> 6)] |= std::uint64_t{1} << (c & 63);
    }
    const auto mergeable = [policy](float v) { return policy == 0 || (policy == 1 && v > 0.5f); };
    const auto valueAt = [&](int cell) { return values[static_cast<std::size_t>(cell)]; };
    std::vector<CoverBox> general, rows;
    detail::coverGreedily(
        known, [&](int start, int cell) { return valueAt(cell) == valueAt(start) && mergeable(valueAt(start)); },
        [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
          general.push_back(CoverBox{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, valueAt(start)});
        });
    detail::coverValues(known, values.data(), mergeable, [&](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
      rows.push_back(CoverBox{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, valueAt(start)});
    });
    ASSERT_TRUE(rows == general) << "trial " << trial << ": " << rows.size() << " boxes against " << general.size();
    boxes += general.size();
    for (const CoverBox& b : general) merged_z += b.lo[2] != b.hi[2] && (b.lo[0] != b.hi[0] || b.lo[1] != b.hi[1]);
  }
  EXPECT_GT(merged_z, 1000u);  // boxes grown in all three directions were compared
  EXPECT_GT(boxes, 100000u);
}
