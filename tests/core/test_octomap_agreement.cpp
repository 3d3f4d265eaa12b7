// Against OctoMap on the same real scans and sensor parameters: the occupied/free class of
// every voxel observed by both maps agrees for at least 99 % of them.
#include <gtest/gtest.h>

#include <octomap/OcTree.h>

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
