// Against OctoMap on the same real scans and sensor parameters: the occupied/free class of
// every voxel observed by both maps agrees for at least 99 % of them. Also the bench's raster
// writer, which the benchmark's memory yardstick relies on.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include <octomap/OcTree.h>

#include "bench.hpp"
#include "octomap_compare.hpp"

#include "test_support.hpp"

using namespace rtog;

namespace {

void runAgreement(SensorModel model, MergePolicy merge) {
  const auto scans = test::loadTumScans(2);
  MapParams p;
  p.resolution = 0.05;
  p.merge = merge;
  OccupancyMap map(p);
  InsertParams ip;
  ip.model = model;
  octomap::OcTree tree(p.resolution);  // OctoMap's default sensor model equals MapParams{}
  for (const auto& s : scans) {
    map.insertPointCloud(s.origin, s.points, ip);
    octomap::Pointcloud cloud;
    for (const auto& q : s.points) cloud.push_back(q.x(), q.y(), q.z());
    const octomap::point3d origin(float(s.origin.x()), float(s.origin.y()), float(s.origin.z()));
    if (model == SensorModel::BeamBased) {
      tree.insertPointCloud(cloud, origin);
    } else {
      for (const auto& q : s.points) tree.updateNode(octomap::point3d(q.x(), q.y(), q.z()), true);
    }
  }
  const bench::Agreement a = bench::compareWithOctomap(map, tree);
  std::cout << "[ octomap ] model " << toString(model) << ", merge " << toString(merge) << ": class agreement "
            << 100.0 * a.ratio() << " % of " << a.both << " voxels seen by both (" << a.only_rtog
            << " only in rtog, " << a.only_octomap << " only in OctoMap)\n";
  EXPECT_GT(a.both, model == SensorModel::BeamBased ? 500000 : 50000);
  EXPECT_GE(a.ratio(), 0.99);
}

TEST(OctoMapAgreement, BeamModel) { runAgreement(SensorModel::BeamBased, MergePolicy::Equal); }
TEST(OctoMapAgreement, EndPointModel) { runAgreement(SensorModel::BeamEndPoint, MergePolicy::Clamped); }

}  // namespace

// The bench's byte raster (its compression yardstick for TUM): one byte per cell over the key
// bounds, x fastest; unknown 0, known log-odds in steps of 0.05 (a known 0 written as 1).
TEST(BenchRaster, OneBytePerCellOverTheBounds) {
  MapParams mp;
  mp.resolution = 1.0;
  mp.merge = MergePolicy::Equal;
  OccupancyMap map(mp);
  // Beams along +x at y = 0.5, z = 0.5: cells x = 0..3 free, x = 4 occupied; one more along +y.
  const std::vector<Eigen::Vector3f> ends = {{4.5f, 0.5f, 0.5f}, {0.5f, 2.5f, 0.5f}};
  map.insertPointCloud(Eigen::Vector3d(0.5, 0.5, 0.5), ends);
  const std::string path = ::testing::TempDir() + "/raster.i8";
  ASSERT_EQ(bench::writeLogOddsRaster(map, path), 5u * 3u * 1u);
  std::ifstream file(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  ASSERT_EQ(bytes.size(), 15u);
  const auto at = [&](int x, int y) {
    return static_cast<int>(static_cast<signed char>(bytes[static_cast<std::size_t>(y * 5 + x)]));
  };
  const auto expected = [&](int x, int y) {
    const auto v = map.logOdds(Key{x, y, 0});
    return v ? static_cast<int>(std::lround(*v * 20.0f)) : 0;
  };
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) EXPECT_EQ(at(x, y), expected(x, y)) << x << ", " << y;
  EXPECT_GT(at(4, 0), 0);  // the hit
  EXPECT_LT(at(1, 0), 0);  // free
  EXPECT_EQ(at(4, 2), 0);  // never seen
}
