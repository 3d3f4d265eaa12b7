// Boost.Geometry's R-tree as a second oracle beside brute force: the same random boxes,
// inserted, removed and moved in both, must give the same box and nearest queries.
#include <gtest/gtest.h>

#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>

#include <limits>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "rtog/core/rtree.hpp"

using namespace rtog;
namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

namespace {

using BgPoint = bg::model::point<double, 3, bg::cs::cartesian>;
using BgBox = bg::model::box<BgPoint>;
using BgValue = std::pair<BgBox, Handle>;

// Inclusive integer boxes meet where closed boxes on the same corners do.
BgBox closed(const Box& b) {
  return BgBox(BgPoint(b.min.x, b.min.y, b.min.z), BgPoint(b.max.x, b.max.y, b.max.z));
}
// The volume a box of cells covers, [min, max + 1) per axis, for distances.
BgBox volume(const Box& b) {
  return BgBox(BgPoint(b.min.x, b.min.y, b.min.z), BgPoint(b.max.x + 1.0, b.max.y + 1.0, b.max.z + 1.0));
}

Box randomBox(std::mt19937& rng, int extent, int max_size) {
  std::uniform_int_distribution<int> pos(-extent, extent), size(0, max_size);
  const Key a{pos(rng), pos(rng), pos(rng)};
  return Box{a, Key{a.x + size(rng), a.y + size(rng), a.z + size(rng)}};
}

TEST(RTreeBoostOracle, BoxAndNearestQueriesAgreeWithBoostGeometry) {
  std::mt19937 rng(29);
  RTree<int> tree;
  bgi::rtree<BgValue, bgi::quadratic<16>> oracle, oracle_volume;  // closed boxes; covered volumes
  std::map<Handle, Box> live;
  std::uniform_real_distribution<double> u(0.0, 1.0), coord(-80.0, 80.0);
  std::size_t compared = 0, nonempty = 0;
  for (int step = 0; step < 3000; ++step) {
    const double r = u(rng);
    if (r < 0.6 || live.size() < 10) {  // overlapping boxes too: inner boxes of either tree may
      const Box b = randomBox(rng, 60, 8);
      const Handle h = tree.insert(b, step);
      live[h] = b;
      oracle.insert({closed(b), h});
      oracle_volume.insert({volume(b), h});
    } else {
      auto it = live.begin();
      std::advance(it, static_cast<long>(u(rng) * static_cast<double>(live.size() - 1)));
      oracle.remove(BgValue{closed(it->second), it->first});
      oracle_volume.remove(BgValue{volume(it->second), it->first});
      if (r < 0.8) {
        tree.remove(it->first);
        live.erase(it);
      } else {
        const Box moved = randomBox(rng, 60, 8);
        tree.updateBox(it->first, moved);
        it->second = moved;
        oracle.insert({closed(moved), it->first});
        oracle_volume.insert({volume(moved), it->first});
      }
    }
    ASSERT_EQ(tree.size(), oracle.size());
    if (step % 25 != 0) continue;
    ASSERT_EQ(tree.checkInvariants(false), "") << "step " << step;
    for (int q = 0; q < 5; ++q) {
      const Box qb = randomBox(rng, 70, 40);
      std::set<Handle> got, want;
      tree.queryBox(qb, [&](Handle h, const Box&) { got.insert(h); });
      std::vector<BgValue> found;
      oracle.query(bgi::intersects(closed(qb)), std::back_inserter(found));
      for (const BgValue& v : found) want.insert(v.second);
      ASSERT_EQ(got, want) << "step " << step;
      nonempty += !want.empty();
      ++compared;
    }
    // Nearest: the same distance (ties may pick different entries).
    const Eigen::Vector3d p(coord(rng), coord(rng), coord(rng));
    const auto hit = tree.nearest(p, [](Handle, const Box&) { return true; });
    ASSERT_TRUE(hit);
    const BgPoint bp(p.x(), p.y(), p.z());
    std::vector<BgValue> nearest;
    oracle_volume.query(bgi::nearest(bp, 1), std::back_inserter(nearest));
    ASSERT_EQ(nearest.size(), 1u);
    EXPECT_DOUBLE_EQ(hit.value, bg::comparable_distance(bp, nearest[0].first)) << "step " << step;
  }
  EXPECT_GT(compared, 500u);
  EXPECT_GT(nonempty, compared / 2);  // most queries found entries
}

}  // namespace
