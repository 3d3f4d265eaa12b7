#include "octomap_compare.hpp"

#include <unordered_map>

namespace rtog::bench {

Agreement compareWithOctomap(const OccupancyMap& map, const octomap::OcTree& tree) {
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
  map.forEachLeaf([&](const Box& b, float v) {
    const bool occ = map.logOddsModel().classify(v) == CellState::Occupied;
    forEachCell(b, [&](const Key& k) {
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

}  // namespace rtog::bench
