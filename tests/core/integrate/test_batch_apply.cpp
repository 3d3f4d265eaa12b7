// Update batches applied together: the union of their marks, occupied winning across batches.
#include <gtest/gtest.h>

#include <vector>

#include "integrate/beam_integrator.hpp"
#include "map/engine_access.hpp"
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
  const auto trace = [&](const OccupancyMap& m, const std::vector<Eigen::Vector3f>& pts, UpdateBatch& batch,
                         InsertStats& s) {
    BeamIntegrator::traceBeams(m.lattice(), origin, pts.data(), pts.size(), {}, nullptr, batch, s);
  };
  const auto apply = [](OccupancyMap& m, std::vector<const UpdateBatch*> batches, const InsertStats& s, int threads) {
    UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Marks, s);
    set.batches = std::move(batches);
    set.threads = threads;
    return MapEngineAccess::of(m).apply(std::move(set));
  };
  trace(together, both, one, s1);
  one.finalize();
  s1 = apply(together, {&one}, s1, 1);
  trace(split, a, first, s2);
  trace(split, b, second, s2);
  first.finalize();
  second.finalize();
  s2 = apply(split, {&second, &first}, s2, 2);
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
