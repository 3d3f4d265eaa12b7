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

// The oracle: the greedy cover cell by cell. From the lowest uncovered cell, an x-run of cells
// that join it, grown along y while a whole row joins, then along z while a whole layer of rows
// does.
template <class Joins>
std::vector<CoverBox> cellByCellCover(BrickMask m, Joins&& joins, const std::vector<float>& value) {
  const auto has = [&](int c) { return (m[static_cast<std::size_t>(c >> 6)] >> (c & 63)) & 1u; };
  std::vector<CoverBox> boxes;
  for (int start = 0; start < kBrickCells; ++start) {
    if (!has(start)) continue;
    const Key s = localKey(start);
    const auto ok = [&](int x, int y, int z) {
      const int c = localIndex(x, y, z);
      return has(c) && joins(start, c);
    };
    int x1 = s.x, y1 = s.y, z1 = s.z;
    while (x1 + 1 < kBrickSize && ok(x1 + 1, s.y, s.z)) ++x1;
    const auto rowOk = [&](int y, int z) {
      for (int x = s.x; x <= x1; ++x)
        if (!ok(x, y, z)) return false;
      return true;
    };
    while (y1 + 1 < kBrickSize && rowOk(y1 + 1, s.z)) ++y1;
    for (bool grow = true; grow && z1 + 1 < kBrickSize;) {
      for (int y = s.y; y <= y1 && grow; ++y) grow = rowOk(y, z1 + 1);
      if (grow) ++z1;
    }
    for (int z = s.z; z <= z1; ++z)
      for (int y = s.y; y <= y1; ++y)
        for (int x = s.x; x <= x1; ++x) {
          const int c = localIndex(x, y, z);
          m[static_cast<std::size_t>(c >> 6)] &= ~(std::uint64_t{1} << (c & 63));
        }
    boxes.push_back(CoverBox{{s.x, s.y, s.z}, {x1, y1, z1}, value[static_cast<std::size_t>(start)]});
  }
  return boxes;
}

// A random brick of few distinct values, sparse to full, blocky (cells copied from the left,
// below or underneath, or only within `layer`) or noisy.
void randomBrick(std::mt19937& rng, int trial, int layer, std::vector<float>& value, BrickMask& known) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const float palette[] = {-2.0f, -0.4f, 0.4f, 0.85f, 3.5f};
  const int distinct = 1 + trial % 5;
  const double density = 0.2 + 0.8 * u(rng), blockiness = u(rng);
  value.assign(kBrickCells, 0.0f);
  known = BrickMask{};
  for (int c = 0; c < kBrickCells; ++c) {
    const bool copy = c > 0 && u(rng) < blockiness;
    const double pick = u(rng);
    const int source = pick < 0.34 && c % kBrickSize > 0 ? c - 1
                       : pick < 0.67 && c >= kBrickSize ? c - kBrickSize
                       : layer < 0                      ? std::max(c - kLayerCells, 0)
                                                        : std::max(c - 1, 0);
    value[static_cast<std::size_t>(c)] = copy ? value[static_cast<std::size_t>(source)]
                                              : palette[static_cast<std::size_t>(static_cast<int>(u(rng) * distinct))];
    if ((layer < 0 || c / kLayerCells == layer) && u(rng) < density)
      known[static_cast<std::size_t>(c >> 6)] |= std::uint64_t{1} << (c & 63);
  }
}

}  // namespace

// Each cover gives the cell-by-cell greedy cover's boxes, in the same order: the planar cache's
// single layer (coverLayer), a brick covered anew from its values (coverValues: insertion's
// graded bricks), and a mask (coverGreedily: fresh cells of one class); with merging on, off and
// only for some values. Cells outside the known mask hold values too (a reused table's), which
// must not join.
TEST(OccupancyMap, EachCoverEqualsTheCellByCellGreedyCover) {
  std::mt19937 rng(23);
  std::size_t merged_z = 0, merged_layer = 0, boxes = 0;
  std::vector<float> value;
  BrickMask known;
  const auto collect = [](std::vector<CoverBox>& out, const std::vector<float>& v) {
    return [&out, &v](const std::uint8_t lo[3], const std::uint8_t hi[3], int start) {
      out.push_back(CoverBox{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, v[static_cast<std::size_t>(start)]});
    };
  };
  for (int trial = 0; trial < 600; ++trial) {
    const int policy = trial % 3, layer = trial % 2 == 0 ? -1 : (trial / 2) % kBrickSize;
    randomBrick(rng, trial, layer, value, known);
    const auto mergeable = [policy](float v) { return policy == 0 || (policy == 1 && v > 0.5f); };
    const auto equal = [&](int start, int cell) {
      return value[static_cast<std::size_t>(cell)] == value[static_cast<std::size_t>(start)] &&
             mergeable(value[static_cast<std::size_t>(start)]);
    };
    const std::vector<CoverBox> expected = cellByCellCover(known, equal, value);
    std::vector<CoverBox> got;
    detail::coverValues(known, value.data(), mergeable, collect(got, value));
    ASSERT_TRUE(got == expected) << "coverValues, trial " << trial << ": " << got.size() << " boxes against "
                                 << expected.size();
    if (layer >= 0) {
      LayerMask layer_known{};
      std::copy(known.begin() + layer * kLayerWords, known.begin() + (layer + 1) * kLayerWords, layer_known.begin());
      std::vector<CoverBox> in_layer;
      detail::coverLayer(layer_known, value.data() + layer * kLayerCells, layer, mergeable,
                         [&](const std::uint8_t lo[3], const std::uint8_t hi[3], float v) {
                           in_layer.push_back(CoverBox{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, v});
                         });
      ASSERT_TRUE(in_layer == expected) << "coverLayer, trial " << trial;
      for (const CoverBox& b : expected) merged_layer += b.lo[0] != b.hi[0] && b.lo[1] != b.hi[1];
    }
    // The mask alone: every cell joins (values only name the boxes' starts).
    const std::vector<CoverBox> all = cellByCellCover(known, [](int, int) { return true; }, value);
    std::vector<CoverBox> masked;
    detail::coverGreedily(known, collect(masked, value));
    ASSERT_TRUE(masked == all) << "coverGreedily, trial " << trial;
    boxes += expected.size();
    for (const CoverBox& b : expected) merged_z += b.lo[2] != b.hi[2] && (b.lo[0] != b.hi[0] || b.lo[1] != b.hi[1]);
  }
  EXPECT_GT(merged_z, 1000u);      // boxes grown in all three directions were compared
  EXPECT_GT(merged_layer, 200u);   // and boxes of more than one row and column within a layer
  EXPECT_GT(boxes, 100000u);
}
