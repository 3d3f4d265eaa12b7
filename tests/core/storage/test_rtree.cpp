// R-tree: randomized mutation sequences keep the invariants; every query equals brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <functional>
#include <set>

#include "rtog/core/rtree.hpp"

using namespace rtog;

namespace {

struct Model {  // brute-force reference: handle -> (box, payload)
  std::map<Handle, std::pair<Box, int>> entries;
};

Box randomBox(std::mt19937& rng, int extent, int max_size) {
  std::uniform_int_distribution<int> pos(-extent, extent), size(0, max_size);
  Key a{pos(rng), pos(rng), pos(rng)};
  return Box{a, Key{a.x + size(rng), a.y + size(rng), a.z + size(rng)}};
}

bool intersectsAny(const Model& m, const Box& b) {
  for (const auto& [h, e] : m.entries)
    if (e.first.intersects(b)) return true;
  return false;
}

void expectQueriesMatch(const RTree<int>& tree, const Model& model, std::mt19937& rng) {
  // Box queries.
  for (int q = 0; q < 20; ++q) {
    const Box qb = randomBox(rng, 60, 30);
    std::set<Handle> got, want;
    tree.queryBox(qb, [&](Handle h, const Box& b) {
      EXPECT_EQ(b, tree.box(h));
      got.insert(h);
    });
    for (const auto& [h, e] : model.entries)
      if (e.first.intersects(qb)) want.insert(h);
    ASSERT_EQ(got, want);
  }
  // Point queries.
  std::uniform_int_distribution<int> pos(-60, 60);
  for (int q = 0; q < 50; ++q) {
    const Key k{pos(rng), pos(rng), pos(rng)};
    Handle want = kNoHandle;
    for (const auto& [h, e] : model.entries)
      if (e.first.contains(k)) want = h;
    ASSERT_EQ(tree.queryPoint(k), want);
  }
  // Ray queries and first hit along a ray.
  std::uniform_real_distribution<double> coord(-70.0, 70.0);
  for (int q = 0; q < 20; ++q) {
    const Eigen::Vector3d o(coord(rng), coord(rng), coord(rng)), e(coord(rng), coord(rng), coord(rng));
    const Eigen::Vector3d d = (e - o).normalized();
    const double len = (e - o).norm();
    std::set<Handle> got, want;
    tree.queryRay(o, d, len, [&](Handle h, const Box&, double, double) { got.insert(h); });
    double best_t = std::numeric_limits<double>::infinity();
    Handle best = kNoHandle;
    for (const auto& [h, en] : model.entries) {
      double t0, t1;
      if (!intersectRay(o, d, len, en.first, t0, t1)) continue;
      want.insert(h);
      if (en.second % 2 == 0 && t0 < best_t) best_t = t0, best = h;
    }
    ASSERT_EQ(got, want);
    const auto hit = tree.firstAlongRay(o, d, len, [&](Handle h, const Box&) { return tree.payload(h) % 2 == 0; });
    if (best == kNoHandle) {
      ASSERT_FALSE(hit);
    } else {
      ASSERT_TRUE(hit);
      ASSERT_DOUBLE_EQ(hit.value, best_t);
    }
  }
  // Nearest with a predicate (odd payloads only).
  for (int q = 0; q < 20; ++q) {
    const Eigen::Vector3d p(coord(rng), coord(rng), coord(rng));
    double best = std::numeric_limits<double>::infinity();
    for (const auto& [h, e] : model.entries)
      if (e.second % 2 == 1) best = std::min(best, squaredDistance(p, e.first));
    const auto hit = tree.nearest(p, [&](Handle h, const Box&) { return tree.payload(h) % 2 == 1; });
    if (!std::isfinite(best)) {
      ASSERT_FALSE(hit);
    } else {
      ASSERT_TRUE(hit);
      ASSERT_DOUBLE_EQ(hit.value, best);
      ASSERT_DOUBLE_EQ(squaredDistance(p, tree.box(hit.handle)), best);
    }
    const auto limited = tree.nearest(p, [](Handle, const Box&) { return true; }, 4.0);
    if (limited) {
      ASSERT_LE(limited.value, 4.0);
    }
  }
  // Bounds and iteration.
  Box bounds = Box::empty();
  for (const auto& [h, e] : model.entries) bounds = bounds.united(e.first);
  ASSERT_EQ(tree.bounds(), bounds);
  std::size_t n = 0;
  tree.forEach([&](Handle h, const Box& b) {
    ++n;
    ASSERT_EQ(model.entries.at(h).first, b);
    ASSERT_EQ(model.entries.at(h).second, tree.payload(h));
  });
  ASSERT_EQ(n, model.entries.size());
}

class RTreeRandomized : public ::testing::TestWithParam<std::tuple<std::uint32_t, std::uint32_t, unsigned>> {};

TEST_P(RTreeRandomized, MutationsKeepInvariantsAndQueriesMatchBruteForce) {
  const auto [max_entries, min_entries, seed] = GetParam();
  std::mt19937 rng(seed);
  RTree<int> tree(RTreeParams{max_entries, min_entries});
  Model model;
  std::uniform_int_distribution<int> op(0, 9), payload(0, 1000);
  for (int step = 0; step < 1500; ++step) {
    const int o = op(rng);
    if (o < 5 || model.entries.empty()) {  // insert a box disjoint from the others
      const Box b = randomBox(rng, 50, 4);
      if (intersectsAny(model, b)) continue;
      const int p = payload(rng);
      const Handle h = tree.insert(b, p);
      ASSERT_EQ(model.entries.count(h), 0u);
      model.entries[h] = {b, p};
    } else if (o < 8) {  // remove a random entry
      auto it = model.entries.begin();
      std::advance(it, std::uniform_int_distribution<std::size_t>(0, model.entries.size() - 1)(rng));
      tree.remove(it->first);
      ASSERT_FALSE(tree.valid(it->first));
      model.entries.erase(it);
    } else {  // grow or shrink an entry (merge/split at the map level)
      auto it = model.entries.begin();
      std::advance(it, std::uniform_int_distribution<std::size_t>(0, model.entries.size() - 1)(rng));
      Box nb = it->second.first;
      const int axis = std::uniform_int_distribution<int>(0, 2)(rng);
      if (o == 8) {
        nb.max[axis] += 1;
      } else if (nb.extent(axis) > 1) {
        nb.max[axis] -= 1;
      }
      const Handle h = it->first;
      auto others = model;
      others.entries.erase(h);
      if (intersectsAny(others, nb)) continue;
      tree.updateBox(h, nb);
      it->second.first = nb;
    }
    ASSERT_EQ(tree.size(), model.entries.size());
    const std::string err = tree.checkInvariants(true);
    ASSERT_TRUE(err.empty()) << "step " << step << ": " << err;
    if (step % 100 == 99) expectQueriesMatch(tree, model, rng);
  }
  expectQueriesMatch(tree, model, rng);
  // Remove everything; the tree must shrink back to an empty leaf.
  while (!model.entries.empty()) {
    tree.remove(model.entries.begin()->first);
    model.entries.erase(model.entries.begin());
    const std::string err = tree.checkInvariants(true);
    ASSERT_TRUE(err.empty()) << err;
  }
  EXPECT_TRUE(tree.empty());
  EXPECT_EQ(tree.height(), 1);
  EXPECT_TRUE(tree.bounds().isEmpty());
}

INSTANTIATE_TEST_SUITE_P(Capacities, RTreeRandomized,
                         ::testing::Values(std::make_tuple(4u, 2u, 1u), std::make_tuple(8u, 3u, 2u),
                                           std::make_tuple(16u, 6u, 3u), std::make_tuple(32u, 8u, 4u)));

class RTreeBulkLoad : public ::testing::TestWithParam<RTree<int>::Packing> {};

TEST_P(RTreeBulkLoad, BuildsAValidPackedTree) {
  for (const std::size_t n : {0u, 1u, 5u, 17u, 100u, 5000u}) {
    std::mt19937 rng(static_cast<unsigned>(n));
    std::vector<std::pair<Box, int>> items;
    // A grid of disjoint unit-ish boxes in random order.
    for (std::size_t i = 0; i < n; ++i) {
      const int x = static_cast<int>(i % 23) * 3, y = static_cast<int>((i / 23) % 19) * 3,
                z = static_cast<int>(i / (23 * 19)) * 3;
      items.push_back({Box{Key{x, y, z}, Key{x + 1, y + 1, z}}, static_cast<int>(i)});
    }
    std::shuffle(items.begin(), items.end(), rng);
    // AsGiven packs runs in the order given, which its callers keep spatial.
    if (GetParam() == RTree<int>::Packing::AsGiven)
      std::sort(items.begin(), items.end(),
                [](const auto& a, const auto& b) { return mortonCode(a.first.min) < mortonCode(b.first.min); });
    RTree<int> tree;
    tree.bulkLoad(items, GetParam());
    ASSERT_EQ(tree.size(), n);
    ASSERT_EQ(tree.checkInvariants(true), "");
    Model model;
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(tree.box(static_cast<Handle>(i)), items[i].first);
      ASSERT_EQ(tree.payload(static_cast<Handle>(i)), items[i].second);
      model.entries[static_cast<Handle>(i)] = items[i];
    }
    expectQueriesMatch(tree, model, rng);
    // The packed tree keeps working under mutation.
    for (std::size_t i = 0; i < n; i += 2) {
      tree.remove(static_cast<Handle>(i));
      model.entries.erase(static_cast<Handle>(i));
      ASSERT_EQ(tree.checkInvariants(true), "");
    }
    expectQueriesMatch(tree, model, rng);
  }
}

TEST(RTreeBulkLoad, AsGivenWithThreadsBuildsTheSameTree) {
  // Enough entries for the leaf level to be split across threads (a thousand nodes a thread).
  std::vector<std::pair<Box, int>> items;
  for (int i = 0; i < 60000; ++i) {
    const int x = (i % 40) * 2, y = ((i / 40) % 40) * 2, z = i / 1600;
    items.push_back({Box{Key{x, y, z}, Key{x, y + 1, z}}, i});
  }
  std::sort(items.begin(), items.end(),
            [](const auto& a, const auto& b) { return mortonCode(a.first.min) < mortonCode(b.first.min); });
  RTree<int> one, three;
  one.bulkLoad(items, RTree<int>::Packing::AsGiven);
  // Three ranges, run last to first: the tree must not depend on the split or its order.
  three.bulkLoad(items, RTree<int>::Packing::AsGiven,
                 [](std::size_t count, const std::function<void(std::size_t, std::size_t)>& fn) {
                   for (std::size_t p = 3; p-- > 0;) fn(count * p / 3, count * (p + 1) / 3);
                 });
  ASSERT_EQ(three.checkInvariants(true), "");
  ASSERT_EQ(three.size(), items.size());
  // The same nodes in the same places: a query visits the same entries in the same order.
  const auto visits = [](const RTree<int>& tree) {
    std::vector<std::pair<Handle, int>> seen;
    tree.queryBox(Box{Key{10, 10, 0}, Key{60, 50, 30}},
                  [&](Handle h, const Box&) { seen.push_back({h, tree.payload(h)}); });
    return seen;
  };
  EXPECT_EQ(visits(one), visits(three));
  EXPECT_FALSE(visits(one).empty());
  for (std::size_t i = 0; i < items.size(); i += 97) ASSERT_EQ(three.box(static_cast<Handle>(i)), items[i].first);
}

INSTANTIATE_TEST_SUITE_P(Packings, RTreeBulkLoad,
                         ::testing::Values(RTree<int>::Packing::SortTileRecursive, RTree<int>::Packing::Morton,
                                           RTree<int>::Packing::AsGiven),
                         [](const ::testing::TestParamInfo<RTree<int>::Packing>& info) {
                           switch (info.param) {
                             case RTree<int>::Packing::Morton: return std::string("Morton");
                             case RTree<int>::Packing::AsGiven: return std::string("AsGiven");
                             default: return std::string("STR");
                           }
                         });

TEST(Key, MortonCodeInterleavesTheCoordinateBits) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int32_t> coord(kKeyMin, kKeyMax);
  std::vector<Key> keys = {Key{kKeyMin, kKeyMin, kKeyMin}, Key{kKeyMax, kKeyMax, kKeyMax}, Key{0, 0, 0},
                           Key{-1, 0, 1}};
  for (int i = 0; i < 1000; ++i) keys.push_back(Key{coord(rng), coord(rng), coord(rng)});
  for (const Key& k : keys) {
    std::uint64_t expected = 0;
    for (int bit = 0; bit < kKeyBits; ++bit)
      for (int a = 0; a < 3; ++a)
        expected |= ((static_cast<std::uint64_t>(k[a] - kKeyMin) >> bit) & 1u) << (3 * bit + a);
    ASSERT_EQ(mortonCode(k), expected) << k.x << " " << k.y << " " << k.z;
  }
  // Z-order: the eight cells of an aligned 2x2x2 block come together, x fastest.
  EXPECT_LT(mortonCode(Key{0, 0, 0}), mortonCode(Key{1, 0, 0}));
  EXPECT_LT(mortonCode(Key{1, 0, 0}), mortonCode(Key{0, 1, 0}));
  EXPECT_LT(mortonCode(Key{1, 1, 1}), mortonCode(Key{2, 0, 0}));
}

TEST(RTree, InvariantCheckerDetectsOverlap) {
  RTree<int> tree;
  tree.insert(Box{Key{0, 0, 0}, Key{2, 2, 2}}, 1);
  EXPECT_EQ(tree.checkInvariants(true), "");
  tree.insert(Box{Key{2, 2, 2}, Key{3, 3, 3}}, 2);  // overlaps the first in one cell
  EXPECT_NE(tree.checkInvariants(true), "");
  EXPECT_EQ(tree.checkInvariants(false), "");
}

TEST(RTree, RejectsBadParametersAndHandles) {
  EXPECT_THROW(RTree<int>(RTreeParams{3, 2}), std::invalid_argument);
  EXPECT_THROW(RTree<int>(RTreeParams{16, 9}), std::invalid_argument);
  RTree<int> tree;
  EXPECT_THROW(tree.insert(Box::empty(), 0), std::invalid_argument);
  EXPECT_THROW(tree.remove(42), std::invalid_argument);
  const Handle h = tree.insert(Box::cell(Key{1, 2, 3}), 7);
  tree.remove(h);
  EXPECT_THROW(tree.remove(h), std::invalid_argument);
}

}  // namespace
