// lmLikelihoodField_Thrun on the 2D view (each cell's term and its logarithm kept) against the
// stock COccupancyGridMap2D holding the same cells: the same double, bit for bit, on real SENA
// scans at many poses, for every option of the field; and the terms forgotten when the options
// change.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include "grid2d_helpers.hpp"

using namespace rtog_test;
using mrpt::poses::CPose3D;

namespace {

using Map = rtog::CRTreeOccupancyGridMap;

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct Variant {
  const char* name;
  void (*set)(Map::TLikelihoodOptions&);
};

void copyField(const Map::TLikelihoodOptions& o, mrpt::maps::COccupancyGridMap2D& g) {
  auto& l = g.likelihoodOptions;
  l.likelihoodMethod = mrpt::maps::COccupancyGridMap2D::lmLikelihoodField_Thrun;
  l.LF_stdHit = o.LF_stdHit, l.LF_zHit = o.LF_zHit, l.LF_zRandom = o.LF_zRandom, l.LF_maxRange = o.LF_maxRange;
  l.LF_decimation = o.LF_decimation, l.LF_maxCorrsDistance = o.LF_maxCorrsDistance;
  l.LF_useSquareDist = o.LF_useSquareDist, l.LF_alternateAverageMethod = o.LF_alternateAverageMethod;
  l.enableLikelihoodCache = o.enableLikelihoodCache;
}

}  // namespace

TEST(LikelihoodField2D, EqualsTheStockGridBitForBit) {
  const SenaFixture& f = senaFixture();
  const auto frames = loadOdometryFrames(dataset(kSena), 40);
  const Variant variants[] = {
      {"defaults", [](Map::TLikelihoodOptions&) {}},
      {"no cache", [](Map::TLikelihoodOptions& o) { o.enableLikelihoodCache = false; }},
      {"square distance", [](Map::TLikelihoodOptions& o) { o.LF_useSquareDist = true; }},
      {"average", [](Map::TLikelihoodOptions& o) { o.LF_alternateAverageMethod = true; }},
      {"narrow, every point", [](Map::TLikelihoodOptions& o) {
         o.LF_stdHit = 0.07f, o.LF_maxCorrsDistance = 0.33f, o.LF_decimation = 1, o.LF_zHit = 0.8f, o.LF_zRandom = 0.2f;
       }},
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> dxy(-0.5, 0.5), dyaw(-0.3, 0.3), far(-40, 40);
  std::size_t compared = 0, outside_some = 0;
  for (const Variant& v : variants) {
    Map m = f.map;
    m.likelihoodOptions.likelihoodMethod = Map::lmLikelihoodField_Thrun;
    v.set(m.likelihoodOptions);
    mrpt::maps::COccupancyGridMap2D stock = stockCopy(*m.gridView());
    copyField(m.likelihoodOptions, stock);
    for (std::size_t i = 1; i < frames.size(); i += 2) {
      auto scan = frames[i].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
      ASSERT_TRUE(scan);
      for (int k = 0; k < 12; ++k) {
        // Near the pose, and some far off (points beyond the grid take the capped term).
        const bool away = k >= 10;
        const CPose3D q = frames[i].pose + CPose3D(away ? far(rng) : dxy(rng), away ? far(rng) : dxy(rng), 0,
                                                   dyaw(rng), 0, 0);
        const double ours = m.computeObservationLikelihood(*scan, q);
        const double ref = stock.computeObservationLikelihood(*scan, q);
        ASSERT_TRUE(sameBits(ours, ref)) << v.name << ", frame " << i << ", pose " << k << ": " << ours << " vs " << ref;
        ++compared;
        outside_some += away;
      }
    }
  }
  EXPECT_EQ(compared, 5u * 20u * 12u);
  EXPECT_GT(outside_some, 0u);
}

// Options changed between calls reach the field: its kept terms are dropped, as the stock
// grid's cache is.
TEST(LikelihoodField2D, KeptTermsFollowTheOptions) {
  const SenaFixture& f = senaFixture();
  Map m = f.map;
  m.likelihoodOptions.likelihoodMethod = Map::lmLikelihoodField_Thrun;
  const double before = m.computeObservationLikelihood(*f.scan, f.pose);
  m.likelihoodOptions.LF_stdHit *= 2;
  const double wider = m.computeObservationLikelihood(*f.scan, f.pose);
  mrpt::maps::COccupancyGridMap2D stock = stockCopy(*m.gridView());
  copyField(m.likelihoodOptions, stock);
  EXPECT_TRUE(sameBits(wider, stock.computeObservationLikelihood(*f.scan, f.pose)));
  EXPECT_NE(before, wider);
  m.likelihoodOptions.LF_stdHit /= 2;
  EXPECT_TRUE(sameBits(before, m.computeObservationLikelihood(*f.scan, f.pose)));
}
