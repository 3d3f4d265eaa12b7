// The occupancy map against a plain reference grid on the real TUM frames, merging,
// queries against brute force, bad input, and serialization.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <sstream>
#include <thread>

#include "storage/brick.hpp"  // brickOf: leaves stay in their brick
#include "test_support.hpp"

using namespace rtog;

namespace {

const std::vector<image::WorldScan>& tumScans() {
  static const std::vector<image::WorldScan> scans = test::loadTumScans(2);  // ~640k beams
  return scans;
}

OccupancyMap buildMap(MergePolicy merge, const InsertParams& ip = {}, double res = 0.05) {
  MapParams p;
  p.resolution = res;
  p.merge = merge;
  OccupancyMap map(p);
  for (const auto& s : tumScans()) {
    const InsertStats st = map.insertPointCloud(s.origin, s.points, ip);
    EXPECT_EQ(st.raysTotal(), s.points.size());
    EXPECT_EQ(map.checkInvariants(), "");
  }
  return map;
}

const test::ReferenceGrid& tumReference(const InsertParams& ip, int which) {
  static std::map<int, test::ReferenceGrid> cache;
  auto it = cache.find(which);
  if (it == cache.end()) {
    test::ReferenceGrid ref{MapParams{}};
    for (const auto& s : tumScans()) ref.insert(s.origin, s.points, ip);
    it = cache.emplace(which, std::move(ref)).first;
  }
  return it->second;
}

TEST(OccupancyMapTum, MergingOffEqualsReferenceGridExactly) {
  const OccupancyMap map = buildMap(MergePolicy::Off);
  test::expectMatchesReference(map, tumReference({}, 0), /*exact=*/true);
  EXPECT_EQ(static_cast<std::int64_t>(map.leafCount()), map.cellCount());
  EXPECT_GT(map.leafCount(), 100000u);
}

TEST(OccupancyMapTum, MergingKeepsEveryCellAndUsesFewerLeaves) {
  const OccupancyMap off = buildMap(MergePolicy::Off);
  for (const MergePolicy policy : {MergePolicy::Clamped, MergePolicy::Equal}) {
    const OccupancyMap merged = buildMap(policy);
    // Both policies only merge bit-identical values, so the log-odds stay exact too.
    test::expectMatchesReference(merged, tumReference({}, 0), /*exact=*/false);
    test::expectMatchesReference(merged, tumReference({}, 0), /*exact=*/true);
    std::cout << "[ merging ] " << toString(policy) << ": " << merged.leafCount() << " leaves for "
              << merged.cellCount() << " cells (" << off.leafCount() << " leaves without merging)\n";
    EXPECT_LT(merged.leafCount(), off.leafCount());
    EXPECT_EQ(merged.cellCount(), off.cellCount());
  }
}

TEST(OccupancyMapTum, EndPointDiscretizedAndMaxRangeEqualReference) {
  InsertParams endpoint;
  endpoint.model = SensorModel::BeamEndPoint;
  test::expectMatchesReference(buildMap(MergePolicy::Off, endpoint), tumReference(endpoint, 1), true);
  InsertParams discretized;
  discretized.discretize = true;
  test::expectMatchesReference(buildMap(MergePolicy::Equal, discretized), tumReference(discretized, 3), true);
  InsertParams limited;
  limited.max_range = 2.0;
  const OccupancyMap map = buildMap(MergePolicy::Equal, limited);
  test::expectMatchesReference(map, tumReference(limited, 2), true);
  // Nothing occupied beyond 2 m of every sensor origin along the beams: no occupied cell
  // farther than 2 m + a cell diagonal from all origins.
  std::int64_t far_occupied = 0;
  map.forEachLeaf([&](const Box& b, float v) {
    if (map.logOddsModel().classify(v) != CellState::Occupied) return;
    forEachCell(b, [&](const Key& k) {
      double best = 1e9;
      for (const auto& s : tumScans()) best = std::min(best, (map.lattice().cellCenter(k) - s.origin).norm());
      if (best > 2.0 + 0.05 * std::sqrt(3.0)) ++far_occupied;
    });
  });
  EXPECT_EQ(far_occupied, 0);
}

// Repeated evidence drives merged cuboids to split and re-merge; the map stays exact.
TEST(OccupancyMap, SplitOnDisagreeingEvidenceChangesOnlyTouchedCells) {
  MapParams p;
  p.resolution = 1.0;
  p.merge = MergePolicy::Clamped;
  OccupancyMap map(p);
  test::ReferenceGrid ref(p);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // A wall at x = 12 seen from the origin many times: free space clamps and merges.
  std::vector<Eigen::Vector3f> wall;
  for (int y = -6; y <= 6; ++y)
    for (int z = -3; z <= 3; ++z) wall.emplace_back(12.5f, y + 0.5f, z + 0.5f);
  for (int i = 0; i < 8; ++i) {
    map.insertPointCloud(Eigen::Vector3d(0.5, 0.5, 0.5), wall);
    ref.insert(Eigen::Vector3d(0.5, 0.5, 0.5), wall, {});
    ASSERT_EQ(map.checkInvariants(), "");
  }
  const std::size_t merged_leaves = map.leafCount();
  EXPECT_LT(static_cast<std::int64_t>(merged_leaves), map.cellCount());
  // Now obstacles appear inside the cleared space at random spots.
  InsertStats total;
  for (int i = 0; i < 20; ++i) {
    std::vector<Eigen::Vector3f> pts;
    for (int j = 0; j < 5; ++j) pts.emplace_back(2.0f + 9.0f * u(rng), -5.0f + 10.0f * u(rng), -2.0f + 4.0f * u(rng));
    total += map.insertPointCloud(Eigen::Vector3d(0.5, 0.5, 0.5), pts);
    ref.insert(Eigen::Vector3d(0.5, 0.5, 0.5), pts, {});
    ASSERT_EQ(map.checkInvariants(), "");
    test::expectMatchesReference(map, ref, true);
  }
  EXPECT_GT(total.leaves_split, 0u);
}

TEST(OccupancyMap, QueriesMatchBruteForceOverCells) {
  InsertParams ip;
  ip.max_range = 3.0;
  const OccupancyMap map = buildMap(MergePolicy::Equal, ip, 0.1);
  const auto& m = map.logOddsModel();
  // Cell table by brute force over the leaves.
  std::unordered_map<Key, float, KeyHash> cells;
  map.forEachLeaf([&](const Box& b, float v) { forEachCell(b, [&](const Key& k) { cells[k] = v; }); });
  const Box bounds = map.keyBounds();
  std::mt19937 rng(5);
  auto randKey = [&] {
    return Key{std::uniform_int_distribution<int>(bounds.min.x - 2, bounds.max.x + 2)(rng),
               std::uniform_int_distribution<int>(bounds.min.y - 2, bounds.max.y + 2)(rng),
               std::uniform_int_distribution<int>(bounds.min.z - 2, bounds.max.z + 2)(rng)};
  };
  for (int i = 0; i < 20000; ++i) {
    const Key k = randKey();
    const auto it = cells.find(k);
    const CellState want = it == cells.end() ? CellState::Unknown : m.classify(it->second);
    ASSERT_EQ(map.state(k), want);
    ASSERT_EQ(map.stateAt(map.lattice().cellCenter(k)), want);
    if (it != cells.end()) {
      ASSERT_EQ(*map.logOdds(k), it->second);
    }
  }
  for (int i = 0; i < 30; ++i) {
    const Key a = randKey(), b = randKey();
    const Box q{Key{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)},
                Key{std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}};
    BoxSummary want;
    forEachCell(q, [&](const Key& k) {
      const auto it = cells.find(k);
      if (it == cells.end()) ++want.unknown;
      else if (m.classify(it->second) == CellState::Occupied) ++want.occupied;
      else ++want.free;
    });
    const BoxSummary got = map.summarize(q);
    ASSERT_EQ(got.occupied, want.occupied);
    ASSERT_EQ(got.free, want.free);
    ASSERT_EQ(got.unknown, want.unknown);
  }
  // Ray casts: the first occupied cell along the ray equals a fine brute-force walk.
  const Eigen::Vector3d origin = tumScans()[0].origin;
  // Aim near real end points (most rays hit) plus some random directions (most miss).
  const auto& pts = tumScans()[0].points;
  std::uniform_real_distribution<double> dir(-1.0, 1.0);
  std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
  int hits = 0;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector3d target = pts[pick(rng)].cast<double>() + 0.05 * Eigen::Vector3d(dir(rng), dir(rng), dir(rng));
    const Eigen::Vector3d d = i % 4 == 0 ? Eigen::Vector3d(dir(rng), dir(rng), dir(rng)).normalized()
                                         : Eigen::Vector3d((target - origin).normalized());
    const auto hit = map.castRay(origin, d, 6.0);
    const Lattice& lat = map.lattice();
    const Key ok = lat.key(origin), ek = lat.key(origin + d * 6.0);
    Key first;
    bool found = false;
    traverseRay(lat.toLattice(origin), lat.toLattice(origin + d * 6.0), ok, ek, [&](const Key& k) {
      if (found) return;
      const auto it = cells.find(k);
      if (it != cells.end() && m.classify(it->second) == CellState::Occupied) first = k, found = true;
    });
    if (!found) {
      const auto it = cells.find(ek);
      if (it != cells.end() && m.classify(it->second) == CellState::Occupied) first = ek, found = true;
    }
    ASSERT_EQ(hit.hit, found) << "ray " << i;
    if (found) {
      ++hits;
      ASSERT_EQ(hit.cell, first) << "ray " << i;
      ASSERT_NEAR(hit.distance, (lat.cellCenter(first) - origin).norm(), 0.1 * std::sqrt(3.0));
    }
  }
  EXPECT_GT(hits, 100);
  // Nearest occupied leaf.
  std::vector<std::pair<Box, float>> leaves;
  map.forEachLeaf([&](const Box& b, float v) { leaves.push_back({b, v}); });
  for (int i = 0; i < 200; ++i) {
    const Key k = randKey();
    const Eigen::Vector3d p = map.lattice().cellCenter(k) + Eigen::Vector3d(0.01, -0.02, 0.03);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& [b, v] : leaves)
      if (m.classify(v) == CellState::Occupied) best = std::min(best, squaredDistance(map.lattice().toLattice(p), b));
    const auto nh = map.nearestOccupied(p, 1e9);
    ASSERT_TRUE(nh.found);
    ASSERT_NEAR(nh.distance, std::sqrt(best) * 0.1, 1e-9);
  }
}

TEST(OccupancyMapTum, ClassCoverKeepsEveryCellsClassInFewerLeaves) {
  const OccupancyMap map = buildMap(MergePolicy::Equal);
  const auto& m = map.logOddsModel();
  std::unordered_map<Key, CellState, KeyHash> want;
  map.forEachLeaf([&](const Box& b, float v) { forEachCell(b, [&](const Key& k) { want[k] = m.classify(v); }); });
  std::unordered_map<Key, CellState, KeyHash> got;
  std::size_t boxes = 0, occupied_boxes = 0;
  const ClassCover cover = map.classCover([&](const Box& b, CellState state) {
    ++boxes;
    occupied_boxes += state == CellState::Occupied;
    ASSERT_EQ(brickOf(b.min), brickOf(b.max)) << toString(b);
    forEachCell(b, [&](const Key& k) { ASSERT_TRUE(got.emplace(k, state).second) << "overlap at " << toString(k); });
  });
  EXPECT_EQ(got, want);
  EXPECT_EQ(cover.leaves(), boxes);
  EXPECT_EQ(cover.occupied, occupied_boxes);
  // Equal-value merging leaves free cells of different log-odds apart; a class cover joins them.
  EXPECT_LT(cover.leaves(), map.leafCount());
  EXPECT_EQ(map.classCover().leaves(), cover.leaves());
}

TEST(OccupancyMapTum, ThreadCountDoesNotChangeTheMap) {
  for (const bool discretize : {false, true}) {
    std::string bytes[2];
    InsertStats stats[2];
    for (const int threads : {1, 2}) {
      MapParams p;
      p.merge = MergePolicy::Equal;
      OccupancyMap map(p);
      InsertParams ip;
      ip.threads = threads;
      ip.discretize = discretize;
      for (const auto& s : tumScans()) stats[threads - 1] += map.insertPointCloud(s.origin, s.points, ip);
      EXPECT_EQ(map.checkInvariants(), "");
      std::ostringstream os;
      map.write(os);
      bytes[threads - 1] = os.str();
    }
    EXPECT_TRUE(bytes[0] == bytes[1]) << "maps differ with discretize=" << discretize;
    EXPECT_TRUE(stats[0] == stats[1]);
  }
  InsertParams bad;
  bad.threads = 0;
  OccupancyMap map;
  EXPECT_THROW(map.insertPointCloud(Eigen::Vector3d::Zero(), tumScans()[0].points, bad), std::invalid_argument);
}

// Insertion buffers come from a pool shared by all maps: maps inserting at the same time, a
// planar one among them, and a map whose insertion threw, must each still build their own map.
TEST(OccupancyMapTum, MapsInsertingAtOnceGetTheirOwnBuffers) {
  std::vector<Eigen::Vector3f> ring;  // a 2D scan: every beam in the origin's z-layer
  for (int i = 0; i < 720; ++i) {
    const double a = i * M_PI / 360.0, r = 2.0 + 3.0 * std::abs(std::sin(3.0 * a));
    ring.emplace_back(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)), 0.01f);
  }
  const auto buildVolumetric = [&] {
    InsertParams ip;
    ip.threads = 2;
    OccupancyMap map;
    for (const auto& s : tumScans()) map.insertPointCloud(s.origin, s.points, ip);
    std::ostringstream os;
    map.write(os);
    return os.str();
  };
  const auto buildPlanar = [&] {
    OccupancyMap map;
    for (int k = 0; k < 40; ++k) {
      const Eigen::Vector3d origin(0.013 * k, -0.007 * k, 0.02);
      std::vector<Eigen::Vector3f> pts;
      for (const auto& q : ring) pts.push_back(q + origin.cast<float>());
      map.insertPointCloud(origin, pts, InsertParams{});
    }
    std::ostringstream os;
    map.write(os);
    return os.str();
  };
  const std::string volumetric = buildVolumetric(), planar = buildPlanar();
  for (int round = 0; round < 3; ++round) {
    std::string at_once[3];
    std::thread a([&] { at_once[0] = buildVolumetric(); });
    std::thread b([&] { at_once[1] = buildPlanar(); });
    at_once[2] = buildVolumetric();
    a.join();
    b.join();
    EXPECT_TRUE(at_once[0] == volumetric && at_once[2] == volumetric) << "round " << round;
    EXPECT_TRUE(at_once[1] == planar) << "round " << round;
  }
  // A throwing insertion gives its buffers back; the next one starts clean, and so does one
  // after the pool was emptied.
  OccupancyMap::releaseInsertBuffers();
  OccupancyMap map;
  const Eigen::Vector3d bad_origin(std::nan(""), 0, 0);
  EXPECT_THROW(map.insertPointCloud(bad_origin, tumScans()[0].points, InsertParams{}), std::exception);
  InsertParams ip;
  ip.threads = 2;
  for (const auto& s : tumScans()) map.insertPointCloud(s.origin, s.points, ip);
  std::ostringstream os;
  map.write(os);
  EXPECT_TRUE(os.str() == volumetric);
}

TEST(OccupancyMap, BadInputIsCountedNotCrashed) {
  OccupancyMap map;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<Eigen::Vector3f> pts = {
      {1.0f, 0.0f, 0.0f},   {nan, 0.0f, 0.0f},  {0.0f, inf, 0.0f}, {0.0f, 0.0f, -inf},
      {0.0f, 0.0f, 0.0f},   // zero-length beam (at the origin)
      {1e9f, 0.0f, 0.0f},   // beyond the key range at 5 cm
      {2.0f, 1.0f, 0.0f}};
  const InsertStats st = map.insertPointCloud(Eigen::Vector3d::Zero(), pts);
  EXPECT_EQ(st.rays_hit, 2u);
  EXPECT_EQ(st.skipped_non_finite, 3u);
  EXPECT_EQ(st.skipped_zero_length, 1u);
  EXPECT_EQ(st.skipped_out_of_range, 1u);
  EXPECT_EQ(st.raysTotal(), pts.size());
  EXPECT_EQ(map.checkInvariants(), "");
  // An empty scan changes nothing.
  const std::size_t leaves = map.leafCount();
  EXPECT_EQ(map.insertPointCloud(Eigen::Vector3d::Zero(), {}).raysTotal(), 0u);
  EXPECT_EQ(map.leafCount(), leaves);
  // A bad origin is an error, not a skip.
  EXPECT_THROW(map.insertPointCloud(Eigen::Vector3d(std::nan(""), 0, 0), pts), std::out_of_range);
  EXPECT_THROW(map.insertPointCloud(Eigen::Vector3d(1e12, 0, 0), pts), std::out_of_range);
  EXPECT_THROW(map.lattice().key(Eigen::Vector3d(0, -1e9, 0)), std::out_of_range);
  // No-return beams clear but mark nothing occupied.
  OccupancyMap clear_only;
  const std::vector<Eigen::Vector3f> beam = {{3.0f, 0.01f, 0.01f}};
  const std::uint8_t no_return = 0;
  const InsertStats nr = clear_only.insertPointCloud(Eigen::Vector3d(0.01, 0.01, 0.01), beam.data(), 1, {}, &no_return);
  EXPECT_EQ(nr.rays_truncated, 1u);
  EXPECT_EQ(nr.cells_occupied, 0u);
  EXPECT_EQ(clear_only.statistics().occupied_cells, 0);
  EXPECT_GT(clear_only.statistics().free_cells, 50);
  // Negative and far (but valid) coordinates work: no preset extent.
  OccupancyMap far;
  const std::vector<Eigen::Vector3f> fp = {{-5000.0f, -4000.0f, -30.0f}};
  far.insertPointCloud(Eigen::Vector3d(-5000.5, -4000.5, -30.5), fp);
  EXPECT_EQ(far.state(far.lattice().key(Eigen::Vector3d(-5000.0, -4000.0, -30.0))), CellState::Occupied);
  EXPECT_EQ(far.checkInvariants(), "");
}

TEST(OccupancyMap, ParametersAreValidated) {
  MapParams p;
  p.resolution = 0.0;
  EXPECT_THROW(OccupancyMap{p}, std::invalid_argument);
  p.resolution = std::nan("");
  EXPECT_THROW(OccupancyMap{p}, std::invalid_argument);
  p = MapParams{};
  p.log_odds.prob_hit = 0.4;
  EXPECT_THROW(OccupancyMap{p}, std::invalid_argument);
  p = MapParams{};
  p.log_odds.clamp_max = 1.0;
  EXPECT_THROW(OccupancyMap{p}, std::invalid_argument);
  EXPECT_THROW(mergePolicyFromString("sometimes"), std::invalid_argument);
  EXPECT_THROW(sensorModelFromString("sonar"), std::invalid_argument);
}

TEST(OccupancyMap, SerializationRoundTripAndCorruption) {
  const OccupancyMap map = buildMap(MergePolicy::Equal, {}, 0.1);
  std::stringstream ss;
  map.write(ss);
  const std::string bytes = ss.str();
  std::istringstream in(bytes);
  const OccupancyMap back = OccupancyMap::read(in);
  EXPECT_EQ(back.checkInvariants(), "");
  EXPECT_EQ(back.leafCount(), map.leafCount());
  std::stringstream again;
  back.write(again);
  EXPECT_EQ(again.str(), bytes) << "a reloaded map must save to the same bytes";
  std::int64_t differing = 0;
  map.forEachLeaf([&](const Box& b, float v) {
    forEachCell(b, [&](const Key& k) { differing += back.logOdds(k) != v; });
  });
  EXPECT_EQ(differing, 0);
  // Truncation anywhere and flipped bits are reported, never crash.
  for (const std::size_t cut : {std::size_t{0}, std::size_t{5}, std::size_t{40}, bytes.size() / 2, bytes.size() - 1}) {
    std::istringstream t(bytes.substr(0, cut));
    EXPECT_THROW(OccupancyMap::read(t), std::runtime_error) << "cut at " << cut;
  }
  std::mt19937 rng(3);
  for (int i = 0; i < 50; ++i) {
    std::string bad = bytes;
    const std::size_t pos = std::uniform_int_distribution<std::size_t>(0, bad.size() - 1)(rng);
    bad[pos] = static_cast<char>(bad[pos] ^ (1 << (i % 8)));
    std::istringstream t(bad);
    EXPECT_THROW(OccupancyMap::read(t), std::runtime_error) << "flip at " << pos;
  }
}

}  // namespace

