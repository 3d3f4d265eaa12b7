// Maps restricted to regions (OccupancyMap::setRegion): the maps of the tiles of a partition of
// space, each fed every scan, hold together the one map built from the same scans, leaf for leaf
// and bit for bit, in both presets, with clamping on, for every kind of update (planar scans, the
// grid's step runs, graded scans, marks, the 3D grid's assigned cells) and 1 or 2 threads.
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <mrpt/obs/CSensoryFrame.h>

#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/map_file.h"
#include "rtog/mrpt/tiled_map.h"
#include "test_helpers.hpp"

namespace {

using rtog::Box;
using rtog::Key;
using Leaf = std::tuple<std::int32_t, std::int32_t, std::int32_t, std::int32_t, std::int32_t, std::int32_t, std::uint32_t>;
using Feed = std::function<void(rtog::CRTreeOccupancyGridMap&)>;

std::vector<Leaf> leavesOf(const rtog::OccupancyMap& m) {
  std::vector<Leaf> out;
  m.forEachLeaf([&](const Box& b, float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    out.emplace_back(b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z, bits);
  });
  std::sort(out.begin(), out.end());
  return out;
}

/// A random partition of the key space into boxes of whole bricks: cut planes across the map's
/// bounds on x, y and (sometimes) z, the outer tiles reaching the key range's ends.
std::vector<Box> randomTiling(const Box& bounds, std::mt19937& rng) {
  std::vector<std::vector<std::int32_t>> cuts(3);  // per axis: the first cell of each tile after the first
  for (int a = 0; a < 3; ++a) {
    const std::int32_t lo = bounds.min[a] >> 4, hi = bounds.max[a] >> 4;
    const int n = a == 2 ? int(rng() % 2) : 1 + int(rng() % 3);
    for (int i = 0; i < n && hi > lo; ++i) cuts[a].push_back(16 * (lo + 1 + std::int32_t(rng() % std::uint32_t(hi - lo))));
    std::sort(cuts[a].begin(), cuts[a].end());
    cuts[a].erase(std::unique(cuts[a].begin(), cuts[a].end()), cuts[a].end());
  }
  const auto spans = [](const std::vector<std::int32_t>& c) {
    std::vector<std::pair<std::int32_t, std::int32_t>> s;
    std::int32_t from = rtog::kKeyMin;
    for (std::int32_t c0 : c) s.emplace_back(from, c0 - 1), from = c0;
    s.emplace_back(from, rtog::kKeyMax);
    return s;
  };
  std::vector<Box> tiles;
  for (const auto& [x0, x1] : spans(cuts[0]))
    for (const auto& [y0, y1] : spans(cuts[1]))
      for (const auto& [z0, z1] : spans(cuts[2])) tiles.push_back(Box{Key{x0, y0, z0}, Key{x1, y1, z1}});
  return tiles;
}

/// The single build, then three random tilings of it: every tile's leaves lie in the tile, and
/// all tiles' leaves together are the single build's.
void expectTilesEqualWhole(const std::string& section, const Feed& feed, unsigned seed,
                           const std::string& creation = "resolution=0.05") {
  auto whole = rtog_test::mapFromSections(creation, section);
  feed(*whole);
  const std::vector<Leaf> want = leavesOf(whole->map());
  ASSERT_GT(want.size(), 1000u);
  std::mt19937 rng(seed);
  for (int round = 0; round < 3; ++round) {
    const std::vector<Box> tiles = randomTiling(whole->map().keyBounds(), rng);
    std::vector<Leaf> got;
    std::size_t nonempty = 0;
    for (const Box& t : tiles) {
      auto part = rtog_test::mapFromSections(creation, section);
      part->map().setRegion(t);
      feed(*part);
      EXPECT_EQ(part->map().checkInvariants(), "");
      part->map().forEachLeaf([&](const Box& b, float) { EXPECT_TRUE(t.contains(b)); });
      const std::vector<Leaf> mine = leavesOf(part->map());
      nonempty += !mine.empty();
      got.insert(got.end(), mine.begin(), mine.end());
    }
    std::sort(got.begin(), got.end());
    EXPECT_GE(nonempty, 2u) << "a tiling that splits nothing tests nothing";
    ASSERT_EQ(got.size(), want.size()) << section << ", " << tiles.size() << " tiles";
    EXPECT_TRUE(got == want) << section << ", " << tiles.size() << " tiles";
  }
}

Feed senaFeed(std::size_t frames, bool blurred = false) {
  return [frames, blurred](rtog::CRTreeOccupancyGridMap& m) {
    static const auto log = rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 80);
    for (std::size_t i = 0; i < std::min(frames, log.size()); ++i)
      for (const auto& obs : *log[i].sf) {
        if (!blurred) {
          m.insertObservation(*obs, log[i].pose);
          continue;
        }
        mrpt::poses::CPose3DPDFGaussian pdf;
        pdf.mean = log[i].pose;
        pdf.cov.setZero();
        pdf.cov(0, 0) = pdf.cov(1, 1) = 0.03 * 0.03;
        pdf.cov(3, 3) = 0.02 * 0.02;
        m.insertObservation(*obs, pdf);
      }
  };
}

Feed tumFeed() {
  return [](rtog::CRTreeOccupancyGridMap& m) {
    static const rtog::image::DepthSequence seq = rtog::image::readTumSequence(RTOG_TEST_TUM_DIR);
    const rtog::InsertParams ip = m.insertionOptions.toInsertParams();
    for (std::size_t i = 0; i < seq.frames.size(); i += 3) {
      const auto s = rtog::image::loadDepthScan(seq.frames[i], seq.intrinsics, 4);
      m.map().insertPointCloud(s.origin, s.points, ip);
    }
  };
}

Feed velodyneFeed() {
  return [](rtog::CRTreeOccupancyGridMap& m) {
    static const auto obs = rtog_test::firstObservation(rtog_test::dataset("test_velodyne_VLP16.rawlog"));
    m.insertObservation(*obs, mrpt::poses::CPose3D(0.3, -0.2, 0.5, 0.1, 0.0, 0.0));
  };
}

TEST(Regions, RejectsBadRegions) {
  rtog::OccupancyMap m;
  EXPECT_THROW(m.setRegion(Box{Key{0, 0, 0}, Key{14, 15, 15}}), std::invalid_argument);
  EXPECT_THROW(m.setRegion(Box{Key{1, 0, 0}, Key{15, 15, 15}}), std::invalid_argument);
  m.setRegion(Box{Key{-16, 0, 0}, Key{15, 31, 15}});
  EXPECT_EQ(m.region().min.x, -16);
  EXPECT_EQ(m.region().max.y, 31);
  m.setRegion(Box::empty());
  EXPECT_TRUE(m.region().isEmpty());
  m.insertPointCloud(Eigen::Vector3d(0.01, 0.01, 0.01), {Eigen::Vector3f(3.0f, 0.01f, 0.01f)});
  EXPECT_THROW(m.setRegion(Box{Key{-16, -16, -16}, Key{15, 15, 15}}), std::logic_error);
}

TEST(Regions, SenaScansBothPresets) {
  for (const char* preset : {"octomap", "mrpt_grid"})
    for (const char* threads : {"1", "2"})
      expectTilesEqualWhole(std::string("sensorModelPreset=") + preset + "\nthreads=" + threads, senaFeed(60), 7);
}

TEST(Regions, SenaGradedScans) {
  expectTilesEqualWhole("sensorModelPreset=octomap\nsensorModel=rangeNoise\nrangeNoiseStd=0.05", senaFeed(40), 11);
  expectTilesEqualWhole("sensorModelPreset=mrpt_grid\nsensorModel=rangeNoise\nrangeNoiseStd=0.05", senaFeed(40), 12);
  expectTilesEqualWhole("sensorModelPreset=mrpt_grid\nposeUncertainty=on", senaFeed(25, true), 13);
  expectTilesEqualWhole("sensorModelPreset=octomap\nposeUncertainty=on", senaFeed(25, true), 14);
}

TEST(Regions, TumFramesBothPresets) {
  for (const char* preset : {"octomap", "mrpt_grid"})
    for (const char* threads : {"1", "2"})
      expectTilesEqualWhole(std::string("sensorModelPreset=") + preset + "\nthreads=" + threads, tumFeed(), 21);
  expectTilesEqualWhole("sensorModelPreset=octomap\nsensorModel=rangeNoise", tumFeed(), 22);
}

TEST(Regions, VelodyneBothPresets) {
  expectTilesEqualWhole("sensorModelPreset=octomap\nthreads=2", velodyneFeed(), 31);
  expectTilesEqualWhole("sensorModelPreset=mrpt_grid\nthreads=2", velodyneFeed(), 32);
}

TEST(Regions, VelodyneIn3DGridSection) {
  // COccupancyGridMap3D's rule (a 3D section: its cells written back as assigned values).
  expectTilesEqualWhole("sensorModelPreset=mrpt_grid", velodyneFeed(), 33,
                        "resolution=0.1\nmin_x=-30\nmax_x=30\nmin_y=-30\nmax_y=30\nmin_z=-3\nmax_z=5");
}

}  // namespace

namespace {

TEST(Regions, TiledMapOnDiskAndItsNeighbourhood) {
  // The TUM frames as four tiles on disk: read whole they are the single build; a robot's
  // neighbourhood loads the tiles meeting its box, and only those.
  auto whole = rtog_test::mapFromSections("resolution=0.05", "sensorModelPreset=octomap");
  tumFeed()(*whole);
  const std::string dir = ::testing::TempDir() + "rtog_tiles_test";
  std::system(("rm -rf '" + dir + "' && mkdir -p '" + dir + "'").c_str());
  std::mt19937 rng(41);
  std::vector<Box> tiles;
  do tiles = randomTiling(whole->map().keyBounds(), rng);
  while (tiles.size() < 4);
  rtog::TiledMapIndex idx;
  idx.resolution = 0.05;
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    auto part = rtog_test::mapFromSections("resolution=0.05", "sensorModelPreset=octomap");
    part->map().setRegion(tiles[i]);
    tumFeed()(*part);
    idx.tiles.push_back(rtog::writeTile(part->map(), dir, "t" + std::to_string(i) + ".rtog"));
  }
  EXPECT_FALSE(rtog::isTiledMap(dir));  // no index yet: not a map
  idx.write(dir);
  ASSERT_TRUE(rtog::isTiledMap(dir));
  EXPECT_TRUE(leavesOf(rtog::loadMapFile(dir)->map()) == leavesOf(whole->map()));
  // A box around the first camera: the tiles it meets, no others.
  const Eigen::Vector3d lo(-2.6, -2.6, 0.0), hi(-2.0, -2.0, 1.0);
  const auto near = rtog::loadTiledMap(dir, lo, hi);
  Key a, b;
  ASSERT_TRUE(whole->map().lattice().tryKey(lo, a) && whole->map().lattice().tryKey(hi, b));
  const Box box{a, b};
  std::vector<Leaf> want;
  for (const Box& t : tiles)
    if (t.intersects(box))
      whole->map().forEachLeafIn(t, [&](const Box& l, float v) {
        if (!t.contains(l)) return;
        std::uint32_t bits;
        std::memcpy(&bits, &v, sizeof bits);
        want.emplace_back(l.min.x, l.min.y, l.min.z, l.max.x, l.max.y, l.max.z, bits);
      });
  std::sort(want.begin(), want.end());
  EXPECT_FALSE(want.empty());
  EXPECT_TRUE(leavesOf(near->map()) == want);
  EXPECT_LT(near->map().leafCount(), whole->map().leafCount());
  // A damaged index is an error naming it, not a smaller map.
  std::system(("echo 'tile t0.rtog 1 2 3' >> '" + dir + "/tiles.index'").c_str());
  EXPECT_THROW(rtog::loadMapFile(dir), std::runtime_error);
}

}  // namespace

namespace {

TEST(Regions, BalancedSlabsCutTheLongerAxisIntoEqualShares) {
  using rtog::kBrickBits;
  using rtog::kKeyMax;
  using rtog::kKeyMin;
  // Ten brick columns across x of equal weight, two across y: two slabs across x, cut after
  // the fifth column; the outer slabs reach the ends of the key range.
  std::vector<std::pair<std::int32_t, double>> x, y{{0, 5.0}, {1, 5.0}};
  for (std::int32_t c = 0; c < 10; ++c) x.emplace_back(c, 1.0);
  auto slabs = rtog::balancedSlabs(x, y, 2);
  ASSERT_EQ(slabs.size(), 2u);
  EXPECT_EQ(slabs[0].min.x, kKeyMin);
  EXPECT_EQ(slabs[0].max.x, (5 << kBrickBits) - 1);
  EXPECT_EQ(slabs[1].min.x, 5 << kBrickBits);
  EXPECT_EQ(slabs[1].max.x, kKeyMax);
  EXPECT_EQ(slabs[0].min.y, kKeyMin);
  EXPECT_EQ(slabs[0].max.y, kKeyMax);
  // The weight, not the extent, places the cut: one heavy column at the low end is a slab alone.
  x[0].second = 9.0;
  slabs = rtog::balancedSlabs(x, y, 2);
  ASSERT_EQ(slabs.size(), 2u);
  EXPECT_EQ(slabs[0].max.x, (1 << kBrickBits) - 1);
  // More slabs than columns: no empty slab, each column a slab at most.
  slabs = rtog::balancedSlabs(y, {{0, 1.0}}, 4);
  EXPECT_LE(slabs.size(), 2u);
  EXPECT_THROW(rtog::balancedSlabs(x, y, 0), std::invalid_argument);
}

}  // namespace
