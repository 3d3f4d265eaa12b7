// Copies of a map share its bricks, brick hash and upper tree (copy on write): a copy costs a
// pointer per brick, a write clones what it touches, and no write changes another copy. Checked
// on the bundled TUM frames against maps built without copying, with the invariants after every
// edit, and with readers of one copy running while another copy is written (TSan runs this).
#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <thread>
#include <vector>

#include "map/engine_access.hpp"
#include "map_cells.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "test_support.hpp"

namespace rtog {
namespace {

using test::cellsOf;

const std::vector<image::WorldScan>& tumScans() {
  static const std::vector<image::WorldScan> scans = test::loadTumScans(4);
  return scans;
}

MapParams params() {
  MapParams p;
  p.resolution = 0.05;
  return p;
}

const LeafIndex& indexOf(const OccupancyMap& m) { return MapEngineAccess::of(m).store.index; }

void insertFrame(OccupancyMap& m, std::size_t i) {
  const auto& s = tumScans()[i % tumScans().size()];
  m.insertPointCloud(s.origin, s.points, InsertParams{});
}

TEST(CopyOnWrite, ACopySharesEveryBrickAndAWriteClonesOnlyWhatItTouches) {
  OccupancyMap base(params());
  for (std::size_t i = 0; i < 4; ++i) insertFrame(base, i);
  const auto before = cellsOf(base);
  OccupancyMap copy(base);
  const std::size_t bricks = indexOf(base).brickCount();
  ASSERT_GT(bricks, 50u);
  EXPECT_EQ(indexOf(base).sharedBricks(), bricks);
  EXPECT_EQ(indexOf(copy).sharedBricks(), bricks);

  // A small edit: one box of cells assigned.
  const Box kb = base.keyBounds();
  const Box box{kb.min, Key{kb.min.x + 3, kb.min.y + 3, kb.min.z + 3}};
  const float value = base.logOddsModel().clampMax();
  copy.assignCells(&box, &value, 1);
  EXPECT_EQ(copy.checkInvariants(), "");
  EXPECT_EQ(base.checkInvariants(), "");
  EXPECT_EQ(cellsOf(base), before) << "a write to a copy changed the original";
  const std::size_t still = indexOf(base).sharedBricks();
  EXPECT_LT(still, bricks);
  EXPECT_GE(still + 8, bricks) << "the edit touches at most the 8 bricks around one corner";

  // A whole frame into the copy: equal to a map that took the same scans without copying.
  insertFrame(copy, 4);
  OccupancyMap fresh(params());
  for (std::size_t i = 0; i < 4; ++i) insertFrame(fresh, i);
  fresh.assignCells(&box, &value, 1);
  insertFrame(fresh, 4);
  EXPECT_EQ(cellsOf(copy), cellsOf(fresh));
  EXPECT_EQ(cellsOf(base), before);
  EXPECT_EQ(copy.checkInvariants(), "");
  EXPECT_EQ(base.checkInvariants(), "");
}

// A family of maps grown by random copies and edits (seed 39): after every step each map holds
// exactly what a map given the same edits without any copy holds, and passes its invariants.
TEST(CopyOnWrite, RandomEditsOnCopiesLeaveEveryOtherCopyAsItWas) {
  struct Member {
    OccupancyMap map;
    std::vector<int> edits;  // frame i >= 0, or -1 - k: the k-th box assignment
  };
  std::mt19937 rng(39);
  std::vector<Member> family;
  family.push_back({OccupancyMap(params()), {}});
  insertFrame(family[0].map, 0);
  family[0].edits.push_back(0);
  const Box kb = family[0].map.keyBounds();
  const auto box = [&](int k) {
    std::mt19937 r(static_cast<std::uint32_t>(k));
    std::uniform_int_distribution<int> x(kb.min.x, kb.max.x), y(kb.min.y, kb.max.y), z(kb.min.z, kb.max.z), s(0, 20);
    const Key lo{x(r), y(r), z(r)};
    return Box{lo, Key{lo.x + s(r), lo.y + s(r), lo.z + s(r) / 4}};
  };
  const auto apply = [&](OccupancyMap& m, int e) {
    if (e >= 0) {
      insertFrame(m, static_cast<std::size_t>(e));
    } else {
      const Box b = box(-1 - e);
      const float v = (-1 - e) % 2 ? m.logOddsModel().clampMin() : 0.7f;
      m.assignCells(&b, &v, 1);
    }
  };
  int boxes = 0;
  for (int step = 0; step < 24; ++step) {
    const std::size_t who = std::uniform_int_distribution<std::size_t>(0, family.size() - 1)(rng);
    if (std::uniform_int_distribution<int>(0, 2)(rng) == 0 && family.size() < 6) {
      family.push_back({OccupancyMap(family[who].map), family[who].edits});
      continue;
    }
    std::vector<test::CellValues> others;
    for (const Member& m : family) others.push_back(cellsOf(m.map));
    const int e = std::uniform_int_distribution<int>(0, 1)(rng) ? static_cast<int>(1 + step % 7) : -1 - boxes++;
    apply(family[who].map, e);
    family[who].edits.push_back(e);
    for (std::size_t i = 0; i < family.size(); ++i) {
      ASSERT_EQ(family[i].map.checkInvariants(), "") << "map " << i << " after step " << step;
      if (i != who) {
        ASSERT_EQ(cellsOf(family[i].map), others[i]) << "map " << i << " changed by an edit of map " << who;
      }
    }
  }
  for (std::size_t i = 0; i < family.size(); ++i) {
    OccupancyMap fresh(params());
    for (const int e : family[i].edits) apply(fresh, e);
    EXPECT_EQ(cellsOf(family[i].map), cellsOf(fresh)) << "map " << i;
  }
  EXPECT_GE(family.size(), 3u);
}

// Readers of one map query it on several threads while a copy sharing its bricks takes scans
// (what a particle filter does with particles on several threads): the readers see the map as
// it was, and TSan sees no race on the shared bricks or their reference counts.
TEST(CopyOnWrite, ConcurrentReadersOfSharedBricksWhileACopyIsWritten) {
  OccupancyMap base(params());
  for (std::size_t i = 0; i < 3; ++i) insertFrame(base, i);
  const auto want = cellsOf(base);
  OccupancyMap writer(base);
  std::atomic<bool> done{false};
  std::atomic<int> mismatches{0}, reads{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 2; ++t)
    readers.emplace_back([&] {
      do {
        if (cellsOf(base) != want) ++mismatches;
        ++reads;
      } while (!done.load());
    });
  for (std::size_t i = 3; i < 6; ++i) {
    insertFrame(writer, i);
    OccupancyMap another(writer);  // copies made and dropped while the readers read
    insertFrame(another, i + 1);
  }
  done = true;
  for (auto& r : readers) r.join();
  EXPECT_EQ(mismatches.load(), 0);
  EXPECT_GE(reads.load(), 2);
  EXPECT_EQ(cellsOf(base), want);
  EXPECT_EQ(writer.checkInvariants(), "");
}

}  // namespace
}  // namespace rtog
