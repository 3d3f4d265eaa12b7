// applyStepRuns (the ordered per-beam rule of MRPT's grids) against brute force: the same runs
// applied cell by cell with forEachRunCell and StepRule::apply into a plain map of cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/occupancy_map.hpp"

using namespace rtog;

namespace {

// Integer-valued steps in sixteenths, saturating asymmetrically, as the mrpt_grid preset's are;
// the no-return step is larger than the free one, so the free kinds' limit is not bound - delta.
StepRule testRule() {
  StepRule r;
  const auto fr = static_cast<std::size_t>(StepKind::Free), ne = static_cast<std::size_t>(StepKind::FreeNoEcho),
             oc = static_cast<std::size_t>(StepKind::Occupied);
  r.delta[fr] = -8.0f / 16, r.delta[ne] = -16.0f / 16, r.delta[oc] = 24.0f / 16;
  r.limit[fr] = r.limit[ne] = -111.0f / 16, r.bound[fr] = r.bound[ne] = -127.0f / 16;
  r.limit[oc] = 103.0f / 16, r.bound[oc] = 127.0f / 16;
  return r;
}

// The same shape in tenths: no power of two divides every number, so the map steps floats.
StepRule offLatticeRule() {
  StepRule r = testRule();
  for (int k = 0; k < 3; ++k) r.delta[k] *= 1.6f, r.limit[k] *= 1.6f, r.bound[k] *= 1.6f;
  r.delta[0] += 0.1f;
  return r;
}

// The map's clamp is the rule's bounds, as the mrpt_grid preset sets it (probability(±127/16)).
MapParams paramsFor(const StepRule& rule) {
  MapParams p;
  p.merge = MergePolicy::Off;
  p.log_odds.clamp_min = 1.0 / (1.0 + std::exp(-double(rule.bound[0])));
  p.log_odds.clamp_max = 1.0 / (1.0 + std::exp(-double(rule.bound[2])));
  return p;
}

struct Variant {
  bool seed_cloud = false;  // the layer first holds OctoMap-rule values (not whole sixteenths)
  bool general = false;     // runs whose axes both move by fractions, some by more than a brick
  bool off_lattice = false;  // offLatticeRule()
};

using Cells = std::map<std::pair<std::int32_t, std::int32_t>, float>;

// Runs in every direction, crossing bricks and the key origin, long enough to saturate cells
// that many runs share (they all start within a few bricks of each other).
std::vector<OccupancyMap::StepRun> randomRuns(std::mt19937& rng, std::size_t n, bool general) {
  std::uniform_int_distribution<std::int32_t> start(-24, 24), slope(-(1 << OccupancyMap::kRunFracBits),
                                                                    1 << OccupancyMap::kRunFracBits);
  std::uniform_int_distribution<std::uint32_t> len(0, 70);
  std::uniform_int_distribution<int> kind(0, 2), coin(0, 3);
  std::vector<OccupancyMap::StepRun> runs;
  for (std::size_t i = 0; i < n; ++i) {
    OccupancyMap::StepRun r{};
    r.x = start(rng), r.y = start(rng);
    // One coordinate moves a whole cell a step, the other a fraction (as a raster does); some
    // runs axis-parallel.
    const bool along_x = coin(rng) < 2;
    const std::int32_t major = (coin(rng) < 2 ? 1 : -1) * (1 << OccupancyMap::kRunFracBits);
    const std::int32_t minor = coin(rng) == 0 ? 0 : slope(rng);
    r.dx = along_x ? major : minor, r.dy = along_x ? minor : major;
    r.count = len(rng);
    if (general) {
      // Neither coordinate a whole cell a step; one run in eight jumps bricks (40 cells a step).
      std::uniform_int_distribution<std::int32_t> any(-(40 << OccupancyMap::kRunFracBits),
                                                      40 << OccupancyMap::kRunFracBits);
      r.dx = coin(rng) == 0 && coin(rng) == 0 ? any(rng) : slope(rng), r.dy = slope(rng);
      r.count = std::min<std::uint32_t>(r.count, 6);
    }
    r.kind = static_cast<StepKind>(kind(rng) == 2 ? 0 : kind(rng));
    r.end = r.kind == StepKind::Free && coin(rng) != 0;
    r.end_x = r.x + start(rng) / 4, r.end_y = r.y + start(rng) / 4;
    runs.push_back(r);
  }
  return runs;
}

}  // namespace

void checkAgainstBruteForce(const Variant& variant) {
  const bool seed_cloud = variant.seed_cloud;
  const StepRule rule = variant.off_lattice ? offLatticeRule() : testRule();
  std::mt19937 rng(1234);
  OccupancyMap map(paramsFor(rule));
  const float prior = map.logOddsModel().prior();
  Cells ref;
  if (seed_cloud) {
    // A planar fan from the origin: OctoMap-rule values (not whole sixteenths) in layer 0.
    std::vector<Eigen::Vector3f> pts;
    for (int a = 0; a < 90; ++a)
      pts.emplace_back(0.8f * std::cos(a * 0.07f), 0.8f * std::sin(a * 0.07f), 0.025f);
    map.insertPointCloud(Eigen::Vector3d(0.01, 0.01, 0.025), pts);
    map.flush();
    map.forEachLeaf([&](const Box& b, float v) {
      for (auto x = b.min.x; x <= b.max.x; ++x)
        for (auto y = b.min.y; y <= b.max.y; ++y)
          if (b.min.z <= 0 && b.max.z >= 0) ref[{x, y}] = v;
    });
    ASSERT_GT(ref.size(), 100u);
  }
  for (int batch = 0; batch < 30; ++batch) {
    const std::vector<OccupancyMap::StepRun> runs = randomRuns(rng, 200, variant.general);
    const std::int32_t z = batch % 3 - 1;
    std::vector<float> after, expected_after;
    std::size_t unchanged = 0, free_steps = 0, occupied_steps = 0;
    for (const auto& r : runs)
      OccupancyMap::forEachRunCell(r, [&](std::int32_t x, std::int32_t y, StepKind k) {
        if (z != 0) return;  // the reference follows layer 0 only
        auto it = ref.emplace(std::make_pair(x, y), prior).first;
        const float prev = it->second;
        it->second = rule.apply(prev, k);
        unchanged += it->second == prev;
        (k == StepKind::Occupied ? occupied_steps : free_steps) += 1;
        expected_after.push_back(it->second);
      });
    const InsertStats st = map.applyStepRuns(z, runs.data(), runs.size(), rule, &after);
    if (z == 0) {
      EXPECT_EQ(after, expected_after) << "batch " << batch;
      EXPECT_EQ(st.cells_unchanged, unchanged);
      EXPECT_EQ(st.cells_free, free_steps);
      EXPECT_EQ(st.cells_occupied, occupied_steps);
    }
    if (batch % 7 == 0) map.flush();  // a covered map takes further steps from its leaves
  }
  ASSERT_EQ(map.checkInvariants(), "");
  // Every reference cell with its value; nothing known in layer 0 that no run touched.
  for (const auto& [xy, v] : ref) {
    const auto got = map.logOdds(Key{xy.first, xy.second, 0});
    ASSERT_TRUE(got.has_value()) << xy.first << "," << xy.second;
    EXPECT_EQ(*got, v) << xy.first << "," << xy.second;
  }
  std::size_t known_in_layer0 = 0;
  map.forEachLeaf([&](const Box& b, float) {
    if (b.min.z <= 0 && b.max.z >= 0)
      known_in_layer0 += static_cast<std::size_t>(b.extent(0) * b.extent(1));
  });
  EXPECT_EQ(known_in_layer0, ref.size());
  // Saturation was reached, so the limits were exercised.
  std::size_t saturated = 0;
  for (const auto& [xy, v] : ref) saturated += v == rule.bound[0] || v == rule.bound[2];
  EXPECT_GT(saturated, variant.general ? 0u : 10u);
}

TEST(StepRuns, EqualBruteForceCellByCellAndStepByStep) { checkAgainstBruteForce({}); }
TEST(StepRuns, EqualBruteForceOverCellsOfTheOtherRule) { checkAgainstBruteForce({true, false, false}); }
TEST(StepRuns, EqualBruteForceWithRunsOfAnySlope) { checkAgainstBruteForce({false, true, false}); }
TEST(StepRuns, EqualBruteForceForARuleOffEveryLattice) { checkAgainstBruteForce({true, false, true}); }

// A planar scan of the other rule into layers the step rule holds in codes (not yet covered)
// gives the map it gives after they were covered.
TEST(StepRuns, APlanarScanOverUncoveredStepsEqualsOneOverCoveredSteps) {
  const StepRule rule = testRule();
  std::mt19937 rng(99);
  const std::vector<OccupancyMap::StepRun> runs = randomRuns(rng, 300, false);
  std::vector<Eigen::Vector3f> pts;
  for (int a = 0; a < 120; ++a) pts.emplace_back(0.9f * std::cos(a * 0.05f), 0.9f * std::sin(a * 0.05f), 0.025f);
  const MapParams p = paramsFor(rule);
  OccupancyMap a(p), b(p);
  a.applyStepRuns(0, runs.data(), runs.size(), rule);
  b.applyStepRuns(0, runs.data(), runs.size(), rule);
  b.flush();
  for (OccupancyMap* m : {&a, &b}) {
    m->insertPointCloud(Eigen::Vector3d(0.01, 0.01, 0.025), pts);
    m->flush();
    ASSERT_EQ(m->checkInvariants(), "");
  }
  std::vector<std::pair<Box, float>> la, lb;
  a.forEachLeaf([&](const Box& box, float v) { la.emplace_back(box, v); });
  b.forEachLeaf([&](const Box& box, float v) { lb.emplace_back(box, v); });
  ASSERT_GT(la.size(), 100u);
  ASSERT_EQ(la.size(), lb.size());
  for (std::size_t i = 0; i < la.size(); ++i) {
    EXPECT_EQ(la[i].first.min, lb[i].first.min);
    EXPECT_EQ(la[i].first.max, lb[i].first.max);
    EXPECT_EQ(la[i].second, lb[i].second);
  }
}

TEST(StepRuns, ACellOutsideTheKeyRangeChangesNothing) {
  OccupancyMap map{MapParams{}};
  const StepRule rule = testRule();
  OccupancyMap::StepRun ok{0, 0, 1 << OccupancyMap::kRunFracBits, 0, 10, StepKind::Free, true, 10, 0};
  map.applyStepRuns(0, &ok, 1, rule);
  map.flush();
  const std::size_t leaves = map.leafCount();
  std::vector<OccupancyMap::StepRun> runs{ok, ok};
  runs[1].x = kKeyMax - 2;  // walks off the key range after three cells
  EXPECT_THROW(map.applyStepRuns(0, runs.data(), runs.size(), rule), std::out_of_range);
  EXPECT_EQ(map.leafCount(), leaves);
  EXPECT_EQ(*map.logOdds(Key{0, 0, 0}), rule.apply(map.logOddsModel().prior(), StepKind::Free));
}

// A run that never leaves its cell steps it count times: the unchanged steps of a stretch longer
// than the codes' counting chunk are counted whole.
TEST(StepRuns, ARunThatStaysOnOneCellCountsEveryStep) {
  const StepRule rule = testRule();
  OccupancyMap map(paramsFor(rule));
  const OccupancyMap::StepRun r{3, -5, 0, 0, 200000, StepKind::Free, false, 0, 0};
  float v = map.logOddsModel().prior();
  std::size_t unchanged = 0;
  for (std::uint32_t k = 0; k < r.count; ++k) {
    const float next = rule.apply(v, StepKind::Free);
    unchanged += next == v;
    v = next;
  }
  const InsertStats st = map.applyStepRuns(0, &r, 1, rule);
  EXPECT_EQ(st.cells_free, r.count);
  EXPECT_EQ(st.cells_unchanged, unchanged);
  EXPECT_GT(unchanged, 150000u);
  EXPECT_EQ(*map.logOdds(Key{3, -5, 0}), v);
}
