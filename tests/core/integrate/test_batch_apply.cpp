// Update batches applied together: the union of their marks, occupied winning across batches.
#include <gtest/gtest.h>

#include <vector>

#include "map/map_engine.hpp"
#include "rtog/core/occupancy_map.hpp"

using namespace rtog;

namespace {

TEST(OccupancyMap, SeveralBatchesApplyAsTheirUnionWithOccupiedWinning) {
  MapParams p;
  p.resolution = 1.0;
  OccupancyMap together(p), split(p);
  const Eigen::Vector3d origin(0.5, 0.5, 0.5);
  // Beam a ends in cell (5, 0, 0); beam b passes through it to (9, 0, 0), across a brick border
  // at 16 only for the third beam.
  const std::vector<Eigen::Vector3f> a{{5.5f, 0.5f, 0.5f}}, b{{9.5f, 0.5f, 0.5f}, {20.5f, 3.5f, 0.5f}};
  std::vector<Eigen::Vector3f> both = a;
  both.insert(both.end(), b.begin(), b.end());
  UpdateBatch one, first, second;
  InsertStats s1, s2;
  together.engine().computeUpdate(origin, both.data(), both.size(), {}, nullptr, one, s1);
  one.finalize();
  together.engine().applyUpdate({&one}, s1);
  split.engine().computeUpdate(origin, a.data(), a.size(), {}, nullptr, first, s2);
  split.engine().computeUpdate(origin, b.data(), b.size(), {}, nullptr, second, s2);
  first.finalize();
  second.finalize();
  split.engine().applyUpdate({&second, &first}, s2, 2);
  EXPECT_EQ(split.checkInvariants(), "");
  EXPECT_EQ(split.state(Key{5, 0, 0}), CellState::Occupied);  // free in `second`, occupied in `first`
  EXPECT_EQ(s2.cells_occupied, s1.cells_occupied);
  EXPECT_EQ(s2.cells_free, s1.cells_free);
  EXPECT_EQ(split.cellCount(), together.cellCount());
  together.forEachLeaf([&](const Box& box, float value) {
    for (std::int32_t x = box.min.x; x <= box.max.x; ++x)
      for (std::int32_t y = box.min.y; y <= box.max.y; ++y)
        for (std::int32_t z = box.min.z; z <= box.max.z; ++z) EXPECT_EQ(split.logOdds(Key{x, y, z}), value);
  });
}

}  // namespace
