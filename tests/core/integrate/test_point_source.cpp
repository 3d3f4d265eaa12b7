// OccupancyMap::insertPointSource: a scan read piece by piece by the insertion threads gives the
// map and the counts of the same points given whole, on every integration path (general,
// planar, graded), and each piece is read by one thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <utility>
#include <vector>

#include "../test_support.hpp"

using namespace rtog;

namespace {

using Leaves = std::vector<std::pair<Box, float>>;

Leaves leavesOf(OccupancyMap& map) {
  map.flush();
  Leaves out;
  map.forEachLeaf([&](const Box& b, float v) { out.emplace_back(b, v); });
  return out;
}

void expectSameLeaves(const Leaves& a, const Leaves& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first.min, b[i].first.min) << "leaf " << i;
    ASSERT_EQ(a[i].first.max, b[i].first.max) << "leaf " << i;
    ASSERT_EQ(a[i].second, b[i].second) << "leaf " << i;
  }
}

// A source over `points` that drops every seventh point, as an observation's invalid pixels
// are dropped, moving the others by `shift` (the frame change a real source makes).
struct DroppingSource {
  const std::vector<Eigen::Vector3f>& points;
  Eigen::Vector3f shift;
  static bool dropped(std::size_t i) { return i % 7 == 3; }
  std::vector<Eigen::Vector3f> kept() const {
    std::vector<Eigen::Vector3f> out;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (!dropped(i)) out.push_back(points[i] + shift);
    return out;
  }
  PointSource source() const {
    return PointSource{points.size(), [this](std::size_t first, std::size_t n, Eigen::Vector3f* out) {
                         std::size_t k = 0;
                         for (std::size_t i = first; i < first + n; ++i)
                           if (!dropped(i)) out[k++] = points[i] + shift;
                         return k;
                       }};
  }
};

// Inserts each scan whole into one map and through a source into another; both must agree.
void expectSourceMatchesWhole(const std::vector<image::WorldScan>& scans, const MapParams& p, const InsertParams& ip) {
  OccupancyMap whole(p), read(p);
  for (const image::WorldScan& s : scans) {
    const DroppingSource src{s.points, Eigen::Vector3f(0.01f, -0.02f, 0.0f)};
    const InsertStats a = whole.insertPointCloud(s.origin, src.kept(), ip);
    const InsertStats b = read.insertPointSource(s.origin, src.source(), ip);
    EXPECT_TRUE(a == b);
    EXPECT_EQ(b.raysTotal(), src.kept().size());
  }
  ASSERT_EQ(read.checkInvariants(), "");
  const Leaves a = leavesOf(whole), b = leavesOf(read);
  ASSERT_GT(a.size(), 1000u);
  expectSameLeaves(a, b);
}

}  // namespace

TEST(PointSource, TumFramesGiveTheMapOfThePointsGivenWhole) {
  const auto scans = test::loadTumScans(2);
  const std::vector<image::WorldScan> three(scans.begin(), scans.begin() + 3);
  for (const double res : {0.05, 0.1})
    for (const bool discretize : {false, true})
      for (const int threads : {1, 2}) {
        SCOPED_TRACE(testing::Message() << "res " << res << " discretize " << discretize << " threads " << threads);
        MapParams p;
        p.resolution = res;
        InsertParams ip;
        ip.discretize = discretize;
        ip.threads = threads;
        expectSourceMatchesWhole(three, p, ip);
      }
}

TEST(PointSource, GradedScansGiveTheMapOfThePointsGivenWhole) {
  const auto scans = test::loadTumScans(4);
  InsertParams ip;
  ip.model = SensorModel::RangeNoise;
  ip.range_noise_std = 0.03;
  expectSourceMatchesWhole({scans[0], scans[5]}, MapParams{}, ip);
}

TEST(PointSource, APlanarScanGoesThroughThePlanarCacheAsWhole) {
  // A level 2D scan: every beam in the origin's z-layer, so the planar cache takes it.
  image::WorldScan scan;
  scan.origin = Eigen::Vector3d(0.31, -0.12, 0.27);
  for (int i = 0; i < 5000; ++i) {
    const double a = 2.0 * M_PI * i / 5000.0, r = 3.0 + std::sin(7.0 * a);
    scan.points.emplace_back(static_cast<float>(scan.origin.x() + r * std::cos(a)),
                             static_cast<float>(scan.origin.y() + r * std::sin(a)), 0.27f);
  }
  OccupancyMap whole{MapParams{}}, read{MapParams{}};
  const DroppingSource src{scan.points, Eigen::Vector3f::Zero()};
  const InsertStats a = whole.insertPointCloud(scan.origin, src.kept());
  const InsertStats b = read.insertPointSource(scan.origin, src.source());
  EXPECT_TRUE(whole.hasPendingCover());
  EXPECT_TRUE(read.hasPendingCover());
  EXPECT_TRUE(a == b);
  expectSameLeaves(leavesOf(whole), leavesOf(read));
}

TEST(PointSource, EachPointIsReadOnceByTheTracingThreads) {
  const auto scans = test::loadTumScans(1);
  const std::vector<Eigen::Vector3f>& pts = scans.front().points;
  std::mutex m;
  std::vector<int> reads(pts.size(), 0);
  std::vector<std::pair<std::size_t, std::size_t>> ranges;
  const PointSource source{pts.size(), [&](std::size_t first, std::size_t n, Eigen::Vector3f* out) {
                             {
                               const std::lock_guard<std::mutex> lock(m);
                               ranges.emplace_back(first, n);
                               for (std::size_t i = first; i < first + n; ++i) ++reads[i];
                             }
                             std::copy(pts.begin() + first, pts.begin() + first + n, out);
                             return n;
                           }};
  InsertParams ip;
  ip.threads = 2;
  OccupancyMap map{MapParams{}};
  const InsertStats stats = map.insertPointSource(scans.front().origin, source, ip);
  EXPECT_EQ(stats.raysTotal(), pts.size());
  // The planar test reads the first piece once more; every other point once. No piece is
  // larger than the 2,048 points a thread keeps on its stack.
  for (std::size_t i = 0; i < pts.size(); ++i) ASSERT_EQ(reads[i], i < 2048 ? 2 : 1) << "point " << i;
  for (const auto& r : ranges) EXPECT_LE(r.second, 2048u);
  EXPECT_GT(ranges.size(), pts.size() / 2048);
}
