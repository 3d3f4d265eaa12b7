// OccupancyMap::fuse under any pose (issue #37): the other map is resampled into this lattice by
// the volume of each placed cuboid inside each cell, so the evidence (sum over cells of l - l0) is
// conserved whatever the pose: a yaw and a sub-cell shift, a general 3D turn, another resolution,
// a half-cell shift. A far pose is a counted skip, never a loop over 1e19 cells.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <set>
#include <unordered_map>

#include <Eigen/Geometry>

#include "integrate/fusion_resample.hpp"
#include "map_cells.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "test_support.hpp"

namespace rtog {
namespace {

using test::cellsOf;

// Clamps out of reach, as the other fusion tests: the resampled values are weighted means of the
// other map's, within its range, so no update is clamped.
MapParams params(double resolution) {
  MapParams p;
  p.resolution = resolution;
  p.merge = MergePolicy::Equal;
  p.log_odds.clamp_min = 1e-9, p.log_odds.clamp_max = 1.0 - 1e-9;
  return p;
}

const OccupancyMap& tumMap() {
  static const OccupancyMap m = [] {
    OccupancyMap out(params(0.1));
    InsertParams ip;
    ip.max_range = 4.0;
    for (const auto& s : test::loadTumScans(4)) out.insertPointCloud(s.origin, s.points, ip);
    return out;
  }();
  return m;
}

/// Sum over cells of l - l0.
double evidence(const OccupancyMap& m) {
  double sum = 0;
  const double l0 = m.logOddsModel().prior();
  m.forEachLeaf([&](const Box& b, float v) { sum += (double(v) - l0) * double(b.volume()); });
  return sum;
}

Eigen::Isometry3d pose(double x, double y, double z, double yaw_deg, double pitch_deg = 0, double roll_deg = 0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translate(Eigen::Vector3d(x, y, z));
  p.rotate(Eigen::AngleAxisd(yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(pitch_deg * M_PI / 180, Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(roll_deg * M_PI / 180, Eigen::Vector3d::UnitX()));
  return p;
}

std::int32_t floorDiv(std::int32_t a, std::int32_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Finding 2 (a): a 17 deg yaw with a sub-cell shift (the 2D clip times a 1D overlap), and a turn
// about all three axes (the cell clipped by the six faces of the placed cuboid): the fused map
// holds the other map's evidence, and the threads do not change it.
TEST(FusionResample, AYawOrA3DTurnWithASubCellShiftConservesTheEvidence) {
  const OccupancyMap& b = tumMap();
  const double want = evidence(b);
  ASSERT_GT(std::fabs(want), 1000.0);
  ASSERT_GT(b.leafCount(), 4 * kResampleBlock);  // blocks for the two threads to share
  for (const auto& [name, p] : {std::pair<const char*, Eigen::Isometry3d>{"yaw", pose(0.237, -0.161, 0.043, 17)},
                                {"3D", pose(0.237, -0.161, 0.043, 17, 6, -4)}}) {
    SCOPED_TRACE(name);
    OccupancyMap two(b.params()), one(b.params());
    const InsertStats st = two.fuse(b, p, 2);
    EXPECT_EQ(st.skipped_out_of_range, 0u);
    EXPECT_EQ(two.checkInvariants(), "");
    const double got = evidence(two);
    std::printf("fused under a %s turn and a sub-cell shift: evidence %.6g of %.6g (relative error %.2g), %lld cells of %lld\n",
                name, got, want, std::fabs(got - want) / std::fabs(want), static_cast<long long>(two.cellCount()),
                static_cast<long long>(b.cellCount()));
    EXPECT_LT(std::fabs(got - want), 1e-4 * std::fabs(want));
    one.fuse(b, p, 1);
    EXPECT_EQ(cellsOf(one), cellsOf(two));
  }
}

// Every kind of placement conserves the evidence, into the same lattice and into one of 0.07 m:
// a quarter turn with a sub-cell shift (1D overlaps), a turn about y alone (a 2D clip about
// another axis), and a yaw or a 3D turn into the other lattice.
TEST(FusionResample, EveryKindOfPlacementConservesTheEvidence) {
  const OccupancyMap& b = tumMap();
  const double want = evidence(b);
  for (const double res : {0.1, 0.07})
    for (const auto& p : {pose(0.03, 0.07, -0.05, 90), pose(0.03, 0.07, -0.05, 0, 23), pose(-0.4, 0.31, 0.02, -41),
                          pose(0.1, 0.2, 0.3, 150, -30, 12)}) {
      OccupancyMap m(params(res));
      EXPECT_EQ(m.fuse(b, p).skipped_out_of_range, 0u);
      EXPECT_EQ(m.checkInvariants(), "");
      EXPECT_LT(std::fabs(evidence(m) - want), 1e-4 * std::fabs(want)) << res << "\n" << p.matrix();
    }
}

// The three exact forms agree where they meet: a yaw with a tilt of 1e-7 deg (clipped in 3D)
// against the yaw alone (2D clip), and a quarter turn off by 1e-7 deg (2D clip) against the
// quarter turn (1D overlaps), cell by cell, into 0.1 m and 0.07 m lattices. A cell only one of
// them knows holds a sliver of the turn (|l| below 1e-5).
TEST(FusionResample, TheExactFormsAgreeWhereTheyMeet) {
  const OccupancyMap& b = tumMap();
  const std::pair<Eigen::Isometry3d, Eigen::Isometry3d> pairs[] = {
      {pose(0.237, -0.161, 0.043, 17), pose(0.237, -0.161, 0.043, 17, 1e-7)},
      {pose(0.03, 0.07, -0.05, 90), pose(0.03, 0.07, -0.05, 90 + 1e-7)}};
  for (const double res : {0.1, 0.07})
    for (const auto& [p, q] : pairs) {
      OccupancyMap mp(params(res)), mq(params(res));
      mp.fuse(b, p);
      mq.fuse(b, q);
      const auto cp = cellsOf(mp), cq = cellsOf(mq);
      std::unordered_map<std::uint64_t, float> in_p(cp.begin(), cp.end()), in_q(cq.begin(), cq.end());
      double worst = 0, sliver = 0;
      for (const auto& [k, v] : cp) {
        const auto it = in_q.find(k);
        if (it == in_q.end()) sliver = std::max(sliver, std::fabs(double(v)));
        else worst = std::max(worst, std::fabs(double(v) - it->second));
      }
      for (const auto& [k, v] : cq)
        if (!in_p.count(k)) sliver = std::max(sliver, std::fabs(double(v)));
      EXPECT_LT(worst, 1e-5) << res;
      EXPECT_LT(sliver, 1e-5) << res;
      EXPECT_GT(cp.size(), b.cellCount() / 2);
    }
}

// Finding 1 (c): into a lattice of twice the cell, every cell of the other map lands in its parent
// cell (no cell lost) with all its evidence; the issue saw 5,084 cells kept.
TEST(FusionResample, IntoACoarserLatticeNoCellIsLost) {
  const OccupancyMap& b = tumMap();
  OccupancyMap coarse(params(0.2));
  EXPECT_EQ(coarse.fuse(b).skipped_out_of_range, 0u);
  EXPECT_EQ(coarse.checkInvariants(), "");
  std::set<std::uint64_t> parents;
  for (const auto& [packed, v] : cellsOf(b)) {
    const Key k = unpackKey(packed);
    parents.insert(packKey(Key{floorDiv(k.x, 2), floorDiv(k.y, 2), floorDiv(k.z, 2)}));
  }
  std::printf("0.1 m into 0.2 m: %lld cells of %zu parents, evidence %.6g of %.6g\n",
              static_cast<long long>(coarse.cellCount()), parents.size(), evidence(coarse), evidence(b));
  EXPECT_EQ(static_cast<std::size_t>(coarse.cellCount()), parents.size());
  EXPECT_LT(std::fabs(evidence(coarse) - evidence(b)), 1e-4 * std::fabs(evidence(b)));
}

// Finding 1 (c): a shift by half a cell on each axis spreads each cell over the 8 it straddles;
// before, a cell centre on a face of the other lattice was dropped (12-100 % lost).
TEST(FusionResample, AHalfCellShiftLosesNothing) {
  const OccupancyMap& b = tumMap();
  OccupancyMap shifted(b.params());
  EXPECT_EQ(shifted.fuse(b, pose(0.05, 0.05, 0.05, 0)).skipped_out_of_range, 0u);
  EXPECT_EQ(shifted.checkInvariants(), "");
  std::set<std::uint64_t> touched;
  for (const auto& [packed, v] : cellsOf(b)) {
    const Key k = unpackKey(packed);
    for (int c = 0; c < 8; ++c) touched.insert(packKey(Key{k.x + (c & 1), k.y + ((c >> 1) & 1), k.z + ((c >> 2) & 1)}));
  }
  std::printf("half-cell shift: %lld cells of %zu straddled, evidence %.6g of %.6g\n",
              static_cast<long long>(shifted.cellCount()), touched.size(), evidence(shifted), evidence(b));
  EXPECT_EQ(static_cast<std::size_t>(shifted.cellCount()), touched.size());
  EXPECT_LT(std::fabs(evidence(shifted) - evidence(b)), 1e-4 * std::fabs(evidence(b)));
}

// Finding 4: the uncertain-pose fusion places the other map by the same rule. Sigma poses of a
// half-cell shift and of a 10 deg yaw put in each cell the mixture of the two conserved
// resamplings' probabilities, and no cell the half-cell shift straddles is lost.
TEST(FusionResample, UncertainPosesMixTheConservedResamplings) {
  const OccupancyMap& b = tumMap();
  const Eigen::Isometry3d p1 = pose(0.05, 0.05, 0.05, 0), p2 = pose(0, 0, 0, 10);
  OccupancyMap mixed(b.params()), r1(b.params()), r2(b.params());
  mixed.fuse(b, std::vector<OccupancyMap::WeightedPose>{{p1, 0.5}, {p2, 0.5}});
  r1.fuse(b, p1);
  r2.fuse(b, p2);
  EXPECT_EQ(mixed.checkInvariants(), "");
  std::set<std::uint64_t> straddled;
  for (const auto& [packed, v] : cellsOf(b)) {
    const Key k = unpackKey(packed);
    for (int c = 0; c < 8; ++c)
      straddled.insert(packKey(Key{k.x + (c & 1), k.y + ((c >> 1) & 1), k.z + ((c >> 2) & 1)}));
  }
  const auto c1 = cellsOf(r1), c2 = cellsOf(r2), cm = cellsOf(mixed);
  std::unordered_map<std::uint64_t, double> want;  // P - P0 = sum over the poses of w (P_i - P0), P0 = 0.5
  for (const auto& [k, v] : c1) want[k] += 0.5 * (probability(v) - 0.5);
  for (const auto& [k, v] : c2) want[k] += 0.5 * (probability(v) - 0.5);
  const std::unordered_map<std::uint64_t, float> got(cm.begin(), cm.end());
  std::size_t lost = 0;
  for (const std::uint64_t k : straddled) lost += got.count(k) == 0;
  EXPECT_EQ(lost, 0u);
  ASSERT_EQ(cm.size(), want.size());
  double worst = 0;
  for (const auto& [k, v] : cm) worst = std::max(worst, std::fabs(double(v) - logit(0.5 + want.at(k))));
  EXPECT_LT(worst, 1e-4);
}

// Finding 3: a pose of 1e18 m (1e19 cells) was a loop of ~9e18 steps; it is a counted skip.
TEST(FusionResample, AFarPoseIsACountedSkip) {
  const OccupancyMap& b = tumMap();
  for (const auto& p : {pose(1e18, 0, 0, 0), pose(1e18, -3e17, 0, 17), pose(0, 1e18, 0, 17, 6, -4),
                        pose(-1e300, 0, 0, 0)}) {
    OccupancyMap c(b.params());
    EXPECT_GT(c.fuse(b, p).skipped_out_of_range, 0u);
    EXPECT_EQ(c.leafCount(), 0u);
    c.fuse(b, std::vector<OccupancyMap::WeightedPose>{{p, 0.5}, {pose(0, 0, 0, 0), 0.5}});
    EXPECT_GT(c.leafCount(), 0u);
  }
}

}  // namespace
}  // namespace rtog
