// A real 2D laser sequence (MRPT's SENA rawlog, odometry poses) inserted as a planar slab
// equals the reference grid cell for cell, with and without merging, through the planar cache
// and without it, read between scans or not, mixed with volumetric scans, copied and threaded.
#include <gtest/gtest.h>

#include <sstream>
#include <thread>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/mrpt/rawlog_poses.h"

#include "map_cells.hpp"
#include "test_support.hpp"

using namespace rtog;

namespace {

struct PlanarScan {
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> points;
};

std::vector<PlanarScan> loadSenaScans(std::size_t max_scans) {
  mrpt::obs::CRawlog log;
  const std::string path = std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
  if (!log.loadFromRawLogFile(path)) throw std::runtime_error("cannot read " + path);
  std::vector<PlanarScan> scans;
  rtog::forEachOdometryObservation(log, [&](const mrpt::obs::CObservation::Ptr& obs, const mrpt::poses::CPose3D& robot,
                                           std::size_t) {
    const auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs);
    if (!scan || scans.size() >= max_scans) return;
    const mrpt::poses::CPose3D sensor = robot + scan->sensorPose;
    PlanarScan ps;
    ps.origin = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
    const std::size_t n = scan->getScanSize();
    const double da = scan->aperture / double(n - 1);
    for (std::size_t j = 0; j < n; ++j) {
      if (!scan->getScanRangeValidity(j)) continue;
      const double a = (scan->rightToLeft ? 1.0 : -1.0) * (-0.5 * scan->aperture + da * double(j));
      const double r = scan->getScanRange(j);
      double gx, gy, gz;
      sensor.composePoint(r * std::cos(a), r * std::sin(a), 0.0, gx, gy, gz);
      ps.points.emplace_back(float(gx), float(gy), float(gz));
    }
    scans.push_back(std::move(ps));
  });
  return scans;
}

TEST(Reference2D, SenaLaserSequenceEqualsReferenceGrid) {
  const auto scans = loadSenaScans(120);
  ASSERT_GE(scans.size(), 100u);
  InsertParams ip;
  ip.max_range = 30.0;
  for (const MergePolicy policy : {MergePolicy::Off, MergePolicy::Clamped, MergePolicy::Equal}) {
    MapParams p;
    p.resolution = 0.05;
    p.merge = policy;
    OccupancyMap map(p);
    test::ReferenceGrid ref(p);
    for (const auto& s : scans) {
      map.insertPointCloud(s.origin, s.points, ip);
      ref.insert(s.origin, s.points, ip);
    }
    EXPECT_TRUE(map.hasPendingCover()) << "the scans should have taken the planar cache";
    ASSERT_EQ(map.checkInvariants(), "");
    EXPECT_FALSE(map.hasPendingCover());
    test::expectMatchesReference(map, ref, /*exact=*/true);
    std::cout << "[ 2D ] merge " << toString(policy) << ": " << map.leafCount() << " leaves, " << map.cellCount()
              << " cells\n";
    if (policy != MergePolicy::Off) {
      EXPECT_LT(static_cast<std::int64_t>(map.leafCount()), map.cellCount());
    }
  }
}

std::string serialized(const OccupancyMap& map) {
  std::ostringstream os;
  map.write(os);
  return os.str();
}

MapParams params2D(MergePolicy policy) {
  MapParams p;
  p.resolution = 0.05;
  p.merge = policy;
  return p;
}

// The cache changes when cells become leaves, never which cells or values: the same scans through
// the general path give the same cells, and every per-scan figure but the leaf counts.
TEST(Reference2D, PlanarCacheEqualsTheGeneralPath) {
  const auto scans = loadSenaScans(60);
  InsertParams cached, general;
  cached.max_range = general.max_range = 30.0;
  general.planar_cache = false;
  for (const MergePolicy policy : {MergePolicy::Off, MergePolicy::Equal}) {
    OccupancyMap a(params2D(policy)), b(params2D(policy));
    test::ReferenceGrid ref(params2D(policy));
    for (const auto& s : scans) {
      InsertStats sa = a.insertPointCloud(s.origin, s.points, cached);
      const InsertStats sb = b.insertPointCloud(s.origin, s.points, general);
      ref.insert(s.origin, s.points, cached);
      EXPECT_FALSE(b.hasPendingCover());
      sa.leaves_created = sb.leaves_created;
      sa.leaves_merged = sb.leaves_merged;
      sa.leaves_split = sb.leaves_split;
      ASSERT_EQ(sa, sb);
    }
    const InsertStats cover = a.flush();
    EXPECT_GT(cover.leaves_created, 0u);
    // Covered, the map holds no more than the same map read from a file: the layers of the
    // whole log (1 KiB of log-odds per touched brick) are released.
    std::istringstream is(serialized(a));
    EXPECT_LT(a.memoryBytes(), OccupancyMap::read(is).memoryBytes() + a.statistics().bricks * 256u);
    EXPECT_EQ(a.checkInvariants(), "");
    EXPECT_EQ(a.cellCount(), b.cellCount());
    test::expectMatchesReference(a, ref, true);
    test::expectMatchesReference(b, ref, true);
  }
}

// Graded 2D scans (range noise; pose blur, traced and moved) go into the planar cache too, with
// the general path's cells and values bit for bit.
TEST(Reference2D, GradedPlanarScansEqualTheGeneralPath) {
  const auto scans = loadSenaScans(40);
  for (const BlurMethod blur : {BlurMethod::Auto, BlurMethod::Trace, BlurMethod::Move}) {
    for (const bool blurred : {false, true}) {
      if (!blurred && blur != BlurMethod::Auto) continue;  // the blur method is for blurred scans only
      InsertParams cached;
      cached.max_range = 30.0;
      cached.model = SensorModel::RangeNoise;
      cached.range_noise_std = 0.03;
      cached.blur_method = blur;
      InsertParams general = cached;
      general.planar_cache = false;
      OccupancyMap a(params2D(MergePolicy::Equal)), b(params2D(MergePolicy::Equal));
      bool pending = false;
      for (const auto& s : scans) {
        InsertStats sa, sb;
        if (blurred) {
          std::vector<PoseMove> moves;
          for (int i = 0; i < 6; ++i) moves.push_back(planarMove(1.0, s.origin, 0.04 * (i % 3 - 1), 0.03 * (i / 3), 0.01 * (i - 2.5)));
          sa = a.insertBlurred(s.origin, s.points, moves, cached);
          sb = b.insertBlurred(s.origin, s.points, moves, general);
        } else {
          sa = a.insertPointCloud(s.origin, s.points, cached);
          sb = b.insertPointCloud(s.origin, s.points, general);
        }
        pending = pending || a.hasPendingCover();
        EXPECT_FALSE(b.hasPendingCover());
        sa.leaves_created = sb.leaves_created;
        sa.leaves_merged = sb.leaves_merged;
        sa.leaves_split = sb.leaves_split;
        ASSERT_EQ(sa, sb);
      }
      EXPECT_TRUE(pending);
      EXPECT_EQ(a.checkInvariants(), "");
      const auto ca = test::cellsOf(a), cb = test::cellsOf(b);
      ASSERT_EQ(ca.size(), cb.size());
      for (std::size_t i = 0; i < ca.size(); ++i) {
        ASSERT_EQ(ca[i].first, cb[i].first);
        ASSERT_EQ(ca[i].second, cb[i].second);
      }
    }
  }
}

// Each read covers the scans so far: queries between scans see every scan.
TEST(Reference2D, ReadsBetweenScansSeeEveryScan) {
  const auto scans = loadSenaScans(25);
  InsertParams ip;
  ip.max_range = 30.0;
  OccupancyMap map(params2D(MergePolicy::Clamped));
  test::ReferenceGrid ref(params2D(MergePolicy::Clamped));
  for (const auto& s : scans) {
    map.insertPointCloud(s.origin, s.points, ip);
    ref.insert(s.origin, s.points, ip);
    ASSERT_TRUE(map.hasPendingCover());
    // A point query first: it alone must bring the scan in.
    const Key end = map.lattice().key(s.points.front().cast<double>());
    ASSERT_TRUE(map.logOdds(end).has_value());
    EXPECT_EQ(*map.logOdds(end), ref.cells().at(end));
    EXPECT_FALSE(map.hasPendingCover());
    ASSERT_EQ(map.checkInvariants(), "");
  }
  test::expectMatchesReference(map, ref, true);
}

// Volumetric scans leave cuboids spanning several z-layers; planar scans in one of those layers
// must cut them exactly, and volumetric scans after planar ones must see the cached cells.
TEST(Reference2D, PlanarAndVolumetricScansMix) {
  const auto scans = loadSenaScans(30);
  InsertParams ip;
  ip.max_range = 30.0;
  for (const MergePolicy policy : {MergePolicy::Clamped, MergePolicy::Equal}) {
    OccupancyMap map(params2D(policy));
    test::ReferenceGrid ref(params2D(policy));
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const auto& s = scans[i];
      if (i % 10 == 0) {
        // A wall of points at eleven heights around the laser's: free columns merged across z.
        std::vector<Eigen::Vector3f> wall;
        for (int h = -5; h <= 5; ++h)
          for (const auto& q : s.points) wall.emplace_back(q.x(), q.y(), q.z() + 0.05f * float(h));
        map.insertPointCloud(s.origin, wall, ip);
        ref.insert(s.origin, wall, ip);
        EXPECT_FALSE(map.hasPendingCover());
      } else {
        // Planar scans, in the laser's layer and one layer up.
        Eigen::Vector3d origin = s.origin;
        std::vector<Eigen::Vector3f> points = s.points;
        if (i % 3 == 0) {
          origin.z() += 0.05;
          for (auto& q : points) q.z() += 0.05f;
        }
        map.insertPointCloud(origin, points, ip);
        ref.insert(origin, points, ip);
      }
      if (i % 5 == 4) {
        ASSERT_EQ(map.checkInvariants(), "");
        test::expectMatchesReference(map, ref, true);
      }
    }
    ASSERT_EQ(map.checkInvariants(), "");
    test::expectMatchesReference(map, ref, true);
  }
}

TEST(Reference2D, CopiesMovesAndFilesOfAPendingMapHoldEveryScan) {
  const auto scans = loadSenaScans(20);
  InsertParams ip;
  ip.max_range = 30.0;
  OccupancyMap map(params2D(MergePolicy::Equal));
  test::ReferenceGrid ref(params2D(MergePolicy::Equal));
  const auto insertAll = [&](OccupancyMap& m) {
    for (const auto& s : scans) m.insertPointCloud(s.origin, s.points, ip);
  };
  insertAll(map);
  for (const auto& s : scans) ref.insert(s.origin, s.points, ip);

  ASSERT_TRUE(map.hasPendingCover());
  const OccupancyMap copy(map);  // a const copy must never need covering later
  EXPECT_FALSE(copy.hasPendingCover());
  test::expectMatchesReference(copy, ref, true);

  OccupancyMap pending(params2D(MergePolicy::Equal));
  insertAll(pending);
  ASSERT_TRUE(pending.hasPendingCover());
  OccupancyMap moved(std::move(pending));
  EXPECT_FALSE(moved.hasPendingCover());
  test::expectMatchesReference(moved, ref, true);

  OccupancyMap assigned(params2D(MergePolicy::Off));
  insertAll(assigned);
  assigned = copy;
  EXPECT_EQ(serialized(assigned), serialized(copy));

  OccupancyMap written(params2D(MergePolicy::Equal));
  insertAll(written);
  ASSERT_TRUE(written.hasPendingCover());
  std::istringstream is(serialized(written));
  const OccupancyMap read = OccupancyMap::read(is);
  test::expectMatchesReference(read, ref, true);
  EXPECT_EQ(serialized(read), serialized(copy));
}

TEST(Reference2D, ConcurrentReadersOfAPendingMapAgree) {
  const auto scans = loadSenaScans(20);
  InsertParams ip;
  ip.max_range = 30.0;
  OccupancyMap map(params2D(MergePolicy::Equal));
  for (const auto& s : scans) map.insertPointCloud(s.origin, s.points, ip);
  const std::int64_t expected_cells = OccupancyMap(map).cellCount();
  for (const auto& s : scans) map.insertPointCloud(s.origin, s.points, ip);  // pending again
  ASSERT_TRUE(map.hasPendingCover());
  std::int64_t cells[2] = {0, 0};
  std::thread other([&] { cells[1] = map.cellCount(); });
  cells[0] = map.cellCount();
  other.join();
  EXPECT_EQ(cells[0], expected_cells);  // the same scans again: no new cells
  EXPECT_EQ(cells[1], expected_cells);
  EXPECT_EQ(map.checkInvariants(), "");
}

// A planar scan long enough to be traced by two threads gives the same map, byte for byte.
TEST(Reference2D, ThreadCountDoesNotChangeAPlanarMap) {
  const auto scans = loadSenaScans(40);
  PlanarScan joined{scans.front().origin, {}};
  for (const auto& s : scans)
    for (const auto& q : s.points) joined.points.emplace_back(q.x(), q.y(), float(joined.origin.z()));
  ASSERT_GT(joined.points.size(), 3u * 4096u);
  std::string bytes[2];
  for (const int threads : {1, 2}) {
    InsertParams ip;
    ip.max_range = 30.0;
    ip.threads = threads;
    OccupancyMap map(params2D(MergePolicy::Equal));
    map.insertPointCloud(joined.origin, joined.points, ip);
    EXPECT_TRUE(map.hasPendingCover());
    map.insertPointCloud(scans.back().origin, scans.back().points, ip);
    bytes[threads - 1] = serialized(map);
  }
  EXPECT_EQ(bytes[0], bytes[1]);
}

// A planar scan too wide for a dense tile grid (here 470 m at 5 cm: 600^2 bricks) takes the
// general path, and cells are the same.
TEST(Reference2D, VeryWidePlanarScanTakesTheGeneralPath) {
  const Eigen::Vector3d origin(0.3, 0.3, 0.31);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 8; ++i)
    points.emplace_back(0.3f + 235.0f * std::cos(0.7f * float(i)), 0.3f + 235.0f * std::sin(0.7f * float(i)), 0.31f);
  InsertParams ip;  // no range limit
  OccupancyMap map(params2D(MergePolicy::Equal));
  test::ReferenceGrid ref(params2D(MergePolicy::Equal));
  map.insertPointCloud(origin, points, ip);
  ref.insert(origin, points, ip);
  EXPECT_FALSE(map.hasPendingCover());
  const std::vector<Eigen::Vector3f> near{Eigen::Vector3f(3.0f, 1.0f, 0.31f)};  // then a small one: cached
  map.insertPointCloud(origin, near, ip);
  ref.insert(origin, near, ip);
  EXPECT_TRUE(map.hasPendingCover());
  EXPECT_EQ(map.checkInvariants(), "");
  test::expectMatchesReference(map, ref, true);
}

}  // namespace
