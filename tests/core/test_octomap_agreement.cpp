// Against OctoMap on the same real scans and sensor parameters: the occupied/free class of
// every voxel observed by both maps agrees for at least 99 % of them.
#include <gtest/gtest.h>

#include <octomap/OcTree.h>

#include "test_support.hpp"

using namespace rtog;

namespace {

struct Agreement {
  std::int64_t both = 0, agree = 0, only_rtog = 0, only_octomap = 0;
  double ratio() const { return both ? double(agree) / double(both) : 0.0; }
};

Agreement compare(const OccupancyMap& map, const octomap::OcTree& tree) {
  // OctoMap keys are lattice keys offset by 2^15 at the finest depth; pruned leaves cover
  // cubes of cells.
  const int offset = 1 << 15;
  std::unordered_map<Key, bool, KeyHash> octo;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k = it.getKey();
    const int size = 1 << (tree.getTreeDepth() - it.getDepth());
    const Key base{(k[0] & ~(size - 1)) - offset, (k[1] & ~(size - 1)) - offset, (k[2] & ~(size - 1)) - offset};
    const bool occ = tree.isNodeOccupied(*it);
    forEachCell(Box{base, Key{base.x + size - 1, base.y + size - 1, base.z + size - 1}},
                [&](const Key& c) { octo[c] = occ; });
  }
  Agreement a;
  std::int64_t rtog_cells = 0;
  map.forEachLeaf([&](const Box& b, float v) {
    const bool occ = map.logOddsModel().classify(v) == CellState::Occupied;
    forEachCell(b, [&](const Key& k) {
      ++rtog_cells;
      const auto it = octo.find(k);
      if (it == octo.end()) {
        ++a.only_rtog;
        return;
      }
      ++a.both;
      a.agree += it->second == occ;
    });
  });
  a.only_octomap = static_cast<std::int64_t>(octo.size()) - a.both;
  return a;
}

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
  const Agreement a = compare(map, tree);
  std::cout << "[ octomap ] model " << toString(model) << ", merge " << toString(merge) << ": class agreement "
            << 100.0 * a.ratio() << " % of " << a.both << " voxels seen by both (" << a.only_rtog
            << " only in rtog, " << a.only_octomap << " only in OctoMap)\n";
  EXPECT_GT(a.both, model == SensorModel::BeamBased ? 500000 : 50000);
  EXPECT_GE(a.ratio(), 0.99);
}

TEST(OctoMapAgreement, BeamModel) { runAgreement(SensorModel::BeamBased, MergePolicy::Equal); }
TEST(OctoMapAgreement, EndPointModel) { runAgreement(SensorModel::BeamEndPoint, MergePolicy::Clamped); }

}  // namespace
