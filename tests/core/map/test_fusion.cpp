// OccupancyMap::fuse, the independent opinion pool (l = l1 + l2 - l0, clamped), on the bundled
// TUM frames: without clamping two halves of the sequence fuse into the map of the whole, with
// clamping each cell is exactly the clamped sum of the halves' values; placed by a shift or a
// quarter turn by whole cells it is cell for cell; placed by uncertain poses it is the mixture of
// the shifted maps; bad poses change nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include <Eigen/Geometry>

#include "map_cells.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "test_support.hpp"

namespace rtog {
namespace {

using test::cellsOf;

MapParams params(bool clamp, double prior = 0.5) {
  MapParams p;
  p.log_odds.prior = prior;
  p.resolution = 0.1;
  p.merge = MergePolicy::Equal;
  if (!clamp) p.log_odds.clamp_min = 1e-9, p.log_odds.clamp_max = 1.0 - 1e-9;
  return p;
}

OccupancyMap build(const std::vector<image::WorldScan>& scans, std::size_t from, std::size_t to, bool clamp,
                   double prior = 0.5) {
  OccupancyMap m(params(clamp, prior));
  InsertParams ip;
  ip.max_range = 4.0;
  for (std::size_t i = from; i < to; ++i) m.insertPointCloud(scans[i].origin, scans[i].points, ip);
  return m;
}

const std::vector<image::WorldScan>& tum() {
  static const auto scans = test::loadTumScans(4);
  return scans;
}

std::unordered_map<std::uint64_t, float> asMap(const test::CellValues& cells) {
  std::unordered_map<std::uint64_t, float> out;
  for (const auto& [k, v] : cells) out.emplace(k, v);
  return out;
}

TEST(Fusion, HalvesWithoutClampingFuseIntoTheWholeSequence) {
  const auto& s = tum();
  ASSERT_EQ(s.size(), 10u);
  // The default prior (l0 = 0) and another, where the prior must be counted once.
  for (const double prior : {0.5, 0.45}) {
    SCOPED_TRACE(prior);
    OccupancyMap whole = build(s, 0, 10, false, prior);
    OccupancyMap a = build(s, 0, 5, false, prior);
    const OccupancyMap b = build(s, 5, 10, false, prior);
    const InsertStats st = a.fuse(b);
    EXPECT_EQ(a.checkInvariants(), "");
    EXPECT_EQ(st.skipped_out_of_range, 0u);
    const auto fused = cellsOf(a), expected = cellsOf(whole);
    ASSERT_EQ(fused.size(), expected.size());
    double worst = 0;
    std::size_t class_differs = 0;
    for (std::size_t i = 0; i < fused.size(); ++i) {
      ASSERT_EQ(fused[i].first, expected[i].first);
      worst = std::max(worst, double(std::fabs(fused[i].second - expected[i].second)));
      class_differs += (fused[i].second >= whole.logOddsModel().prior()) !=
                       (expected[i].second >= whole.logOddsModel().prior());
    }
    std::printf("fusion without clamping, prior %.2f: %zu cells, largest difference from one build %.3g\n", prior,
                fused.size(), worst);
    // The same sums in another order: float rounding only.
    EXPECT_LT(worst, 1e-6);
    EXPECT_EQ(class_differs, 0u);
    // One thread or two: the same map.
    OccupancyMap one = build(s, 0, 5, false, prior);
    one.fuse(b, Eigen::Isometry3d::Identity(), 1);
    EXPECT_EQ(cellsOf(one), fused);
  }
}

TEST(Fusion, WithClampingEachCellIsTheClampedSumOfTheHalves) {
  const auto& s = tum();
  const OccupancyMap a = build(s, 0, 5, true), b = build(s, 5, 10, true);
  OccupancyMap f = a;
  f.fuse(b);
  EXPECT_EQ(f.checkInvariants(), "");
  const LogOddsModel& model = f.logOddsModel();
  ASSERT_EQ(model.prior(), 0.0f);
  const auto ca = asMap(cellsOf(a)), cb = asMap(cellsOf(b));
  std::size_t both = 0, differs_from_whole = 0;
  const auto whole = asMap(cellsOf(build(s, 0, 10, true)));
  for (const auto& [k, v] : cellsOf(f)) {
    const auto ia = ca.find(k), ib = cb.find(k);
    ASSERT_TRUE(ia != ca.end() || ib != cb.end());
    // The exact difference from one build: the halves are clamped apart, then summed and clamped.
    const float want = ia == ca.end()   ? ib->second
                       : ib == cb.end() ? ia->second
                                        : model.update(ia->second, ib->second - model.prior());
    ASSERT_EQ(v, want);
    both += ia != ca.end() && ib != cb.end();
    differs_from_whole += whole.at(k) != v;
  }
  EXPECT_EQ(cellsOf(f).size(), whole.size());
  EXPECT_GT(both, 1000u);
  std::printf("fusion with clamping: %zu cells, %zu in both halves, %zu differ from one build\n", whole.size(), both,
              differs_from_whole);
  EXPECT_GT(differs_from_whole, 0u);  // a cell clamped in a half: the test sees the difference
}

TEST(Fusion, AShiftOrQuarterTurnByWholeCellsMovesEveryCell) {
  const auto& s = tum();
  const OccupancyMap b = build(s, 0, 3, true);
  const double r = b.resolution();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(3 * r, -2 * r, 5 * r));
  pose.rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  OccupancyMap moved(b.params());
  EXPECT_EQ(moved.fuse(b, pose).skipped_out_of_range, 0u);
  EXPECT_EQ(moved.checkInvariants(), "");
  const auto got = asMap(cellsOf(moved));
  const auto src = cellsOf(b);
  ASSERT_EQ(got.size(), src.size());
  for (const auto& [packed, v] : src) {
    const Key k = unpackKey(packed);
    // (x, y, z) -> (-y - 1, x, z) by the quarter turn of cell (not point) coordinates, then the shift.
    const Key to{-k.y - 1 + 3, k.x - 2, k.z + 5};
    const auto it = got.find(packKey(to));
    ASSERT_TRUE(it != got.end());
    EXPECT_EQ(it->second, v);
  }
}

TEST(Fusion, ABadPoseOrItselfIsRefusedAndChangesNothing) {
  const auto& s = tum();
  OccupancyMap a = build(s, 0, 2, true);
  const OccupancyMap b = build(s, 2, 4, true);
  std::ostringstream before;
  a.write(before);
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 2.0;
  Eigen::Isometry3d nan = Eigen::Isometry3d::Identity();
  nan.translation().x() = std::nan("");
  Eigen::Isometry3d mirror = Eigen::Isometry3d::Identity();
  mirror.linear()(0, 0) = -1.0;
  EXPECT_THROW(a.fuse(b, scaled), std::invalid_argument);
  EXPECT_THROW(a.fuse(b, nan), std::invalid_argument);
  EXPECT_THROW(a.fuse(b, mirror), std::invalid_argument);
  EXPECT_THROW(a.fuse(b, Eigen::Isometry3d::Identity(), 0), std::invalid_argument);
  EXPECT_THROW(a.fuse(a), std::invalid_argument);
  std::ostringstream after;
  a.write(after);
  EXPECT_EQ(before.str(), after.str());
  // A map placed beyond the key range: its cells there are left out and counted.
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation().x() = 1e12;
  OccupancyMap c(a.params());
  EXPECT_GT(c.fuse(b, far).skipped_out_of_range, 0u);
  EXPECT_EQ(c.leafCount(), 0u);
}

// Placed by uncertain poses (a registration's sigma points), each cell takes the mixture over the
// poses of the other map's P(occupied) there, the prior where a pose leaves it outside the other
// map's cells: checked cell by cell against that sum over shifts by whole cells.
TEST(Fusion, UncertainPosesFuseTheMixtureOfTheOtherMapsProbabilities) {
  const auto& s = tum();
  const OccupancyMap b = build(s, 0, 2, true);
  const double r = b.resolution();
  std::vector<OccupancyMap::WeightedPose> poses;
  const std::pair<int, double> shifts[] = {{-1, 0.25}, {0, 0.5}, {2, 0.25}};
  for (const auto& [dx, w] : shifts) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translate(Eigen::Vector3d(dx * r, 0, 0));
    poses.push_back({t, w});
  }
  OccupancyMap a(b.params());
  a.fuse(b, poses);
  EXPECT_EQ(a.checkInvariants(), "");
  const auto src = asMap(cellsOf(b));
  const auto got = asMap(cellsOf(a));
  const double p0 = probability(b.logOddsModel().prior());
  std::unordered_map<std::uint64_t, double> expected, known;
  for (const auto& [packed, v] : src) {
    const Key k = unpackKey(packed);
    for (const auto& [dx, w] : shifts) {
      const std::uint64_t to = packKey(Key{k.x + dx, k.y, k.z});
      expected[to] += w * probability(v);
      known[to] += w;
    }
  }
  ASSERT_EQ(got.size(), expected.size());
  double worst = 0;
  for (const auto& [packed, m] : expected) {
    const double p = m + (1.0 - known[packed]) * p0;
    const auto it = got.find(packed);
    ASSERT_TRUE(it != got.end());
    // The map's clamps bound the result as any update.
    const float want = a.logOddsModel().update(a.logOddsModel().prior(), static_cast<float>(logit(p)) - a.logOddsModel().prior());
    worst = std::max(worst, double(std::fabs(it->second - want)));
  }
  EXPECT_LT(worst, 1e-5);
  // One pose of weight 1 is the plain fusion; bad weights change nothing.
  OccupancyMap one(b.params()), plain(b.params());
  one.fuse(b, std::vector<OccupancyMap::WeightedPose>{{Eigen::Isometry3d::Identity(), 1.0}});
  plain.fuse(b);
  EXPECT_EQ(cellsOf(one), cellsOf(plain));
  std::ostringstream before;
  a.write(before);
  EXPECT_THROW(a.fuse(b, std::vector<OccupancyMap::WeightedPose>{}), std::invalid_argument);
  EXPECT_THROW(a.fuse(b, std::vector<OccupancyMap::WeightedPose>{{Eigen::Isometry3d::Identity(), 0.5}}), std::invalid_argument);
  EXPECT_THROW(a.fuse(b, std::vector<OccupancyMap::WeightedPose>{{Eigen::Isometry3d::Identity(), -1.0},
                                                                  {Eigen::Isometry3d::Identity(), 2.0}}),
               std::invalid_argument);
  std::ostringstream after;
  a.write(after);
  EXPECT_EQ(before.str(), after.str());
}

}  // namespace
}  // namespace rtog
