// OccupancyMap::assignCells, the public way to set cell values (priors, imports; read() too):
// checked cell by cell against a brute-force model of the map on the bundled TUM frames, for a
// map without leaves (the boxes become its leaves) and one with leaves (bricks covered anew).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>

#include "map_cells.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "test_support.hpp"

namespace rtog {
namespace {

using test::cellsOf;

MapParams params(MergePolicy merge) {
  MapParams p;
  p.resolution = 0.1;
  p.merge = merge;
  return p;
}

// Disjoint random boxes around the TUM map's cells, some across brick borders, with values the
// model can hold (clamped ones too, so that merged leaves are possible).
void randomBoxes(const OccupancyMap& m, std::uint32_t seed, std::vector<Box>& boxes, std::vector<float>& values) {
  std::mt19937 rng(seed);
  const Box bounds = m.keyBounds();
  std::uniform_int_distribution<int> dx(bounds.min.x, bounds.max.x), dy(bounds.min.y, bounds.max.y),
      dz(bounds.min.z, bounds.max.z), size(0, 20), pick(0, 3);
  const LogOddsModel& model = m.logOddsModel();
  const float choices[] = {model.clampMin(), model.clampMax(), 0.85f, -0.4f};
  std::map<std::uint64_t, bool> used;
  while (boxes.size() < 60) {
    const Key lo{dx(rng), dy(rng), dz(rng)};
    const Box b{lo, Key{lo.x + size(rng), lo.y + size(rng) / 4, lo.z + size(rng) / 10}};
    bool free = true;
    for (std::int32_t z = b.min.z; z <= b.max.z && free; ++z)
      for (std::int32_t y = b.min.y; y <= b.max.y && free; ++y)
        for (std::int32_t x = b.min.x; x <= b.max.x && free; ++x) free = !used.count(packKey(Key{x, y, z}));
    if (!free) continue;
    for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
      for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
        for (std::int32_t x = b.min.x; x <= b.max.x; ++x) used[packKey(Key{x, y, z})] = true;
    boxes.push_back(b);
    values.push_back(choices[pick(rng)]);
  }
}

// The brute-force model: `before`'s cells with each box's cells set to its value.
std::map<std::uint64_t, float> expected(const test::CellValues& before, const std::vector<Box>& boxes,
                                        const std::vector<float>& values) {
  std::map<std::uint64_t, float> want(before.begin(), before.end());
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::int32_t z = boxes[i].min.z; z <= boxes[i].max.z; ++z)
      for (std::int32_t y = boxes[i].min.y; y <= boxes[i].max.y; ++y)
        for (std::int32_t x = boxes[i].min.x; x <= boxes[i].max.x; ++x) want[packKey(Key{x, y, z})] = values[i];
  return want;
}

OccupancyMap tumMap(MergePolicy merge) {
  static const auto scans = test::loadTumScans(4);
  OccupancyMap m(params(merge));
  InsertParams ip;
  ip.max_range = 4.0;
  for (std::size_t i = 0; i < 3; ++i) m.insertPointCloud(scans[i].origin, scans[i].points, ip);
  return m;
}

TEST(AssignCells, SetsEveryCellOfTheBoxesAndNoOtherOnAMapWithLeaves) {
  for (const MergePolicy merge : {MergePolicy::Clamped, MergePolicy::Off, MergePolicy::Equal}) {
    SCOPED_TRACE(static_cast<int>(merge));
    OccupancyMap m = tumMap(merge);
    std::vector<Box> boxes;
    std::vector<float> values;
    randomBoxes(m, 7, boxes, values);
    const auto want = expected(cellsOf(m), boxes, values);
    m.assignCells(boxes.data(), values.data(), boxes.size());
    EXPECT_EQ(m.checkInvariants(), "");
    const auto got = cellsOf(m);
    ASSERT_EQ(got.size(), want.size());
    for (const auto& [k, v] : got) ASSERT_EQ(v, want.at(k)) << toString(unpackKey(k));
    // A value kept apart by the merge policy never sits in a merged leaf.
    m.forEachLeaf([&](const Box& b, float v) {
      if (b.volume() > 1) {
        EXPECT_NE(merge, MergePolicy::Off) << toString(b) << " " << v;
      }
    });
  }
}

TEST(AssignCells, AMapWithoutLeavesTakesTheBoxesAsItsLeavesCutAtBrickBorders) {
  const OccupancyMap src = tumMap(MergePolicy::Equal);
  std::vector<Box> boxes;
  std::vector<float> values;
  src.forEachLeaf([&](const Box& b, float v) { boxes.push_back(b), values.push_back(v); });
  OccupancyMap copy(src.params());
  const InsertStats st = copy.assignCells(boxes.data(), values.data(), boxes.size());
  EXPECT_EQ(copy.checkInvariants(), "");
  EXPECT_EQ(copy.leafCount(), src.leafCount());
  EXPECT_EQ(cellsOf(copy), cellsOf(src));
  EXPECT_EQ(static_cast<std::int64_t>(st.cells_free + st.cells_occupied), src.cellCount());
  std::ostringstream a, b;
  src.write(a);
  copy.write(b);
  EXPECT_EQ(a.str(), b.str());
  // One box across eight bricks: cut into eight leaves.
  OccupancyMap one(src.params());
  const Box across{Key{-3, -3, -3}, Key{4, 4, 4}};
  const float v = one.logOddsModel().clampMax();
  one.assignCells(&across, &v, 1);
  EXPECT_EQ(one.leafCount(), 8u);
  EXPECT_EQ(one.cellCount(), across.volume());
  EXPECT_EQ(one.checkInvariants(), "");
}

TEST(AssignCells, BadBoxesAndValuesThrowAndChangeNothing) {
  OccupancyMap m = tumMap(MergePolicy::Clamped);
  const auto before = cellsOf(m);
  const float ok = 0.5f;
  const Box a{Key{0, 0, 0}, Key{3, 3, 0}}, overlapping{Key{3, 3, 0}, Key{5, 5, 0}};
  const std::vector<Box> two{a, overlapping};
  const std::vector<float> vals{ok, ok};
  EXPECT_THROW(m.assignCells(two.data(), vals.data(), 2), std::invalid_argument);
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          m.logOddsModel().clampMax() + 0.5f, m.logOddsModel().clampMin() - 0.5f}) {
    const std::vector<float> v2{ok, bad};
    const std::vector<Box> b2{a, Box{Key{10, 10, 0}, Key{10, 10, 0}}};
    EXPECT_THROW(m.assignCells(b2.data(), v2.data(), 2), std::invalid_argument) << bad;
  }
  const Box empty = Box::empty(), beyond{Key{kKeyMax - 1, 0, 0}, Key{kKeyMax + 1, 0, 0}},
            huge{Key{kKeyMin, kKeyMin, kKeyMin}, Key{kKeyMax, kKeyMax, kKeyMax}};
  for (const Box& b : {empty, beyond, huge}) EXPECT_THROW(m.assignCells(&b, &ok, 1), std::invalid_argument) << toString(b);
  EXPECT_EQ(cellsOf(m), before);
  EXPECT_EQ(m.checkInvariants(), "");
}

}  // namespace
}  // namespace rtog
