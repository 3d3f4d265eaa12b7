#include "integrate/cell_assignment.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "integrate/insert_scratch.hpp"
#include "storage/map_store.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {
namespace {

const char* const kWhat = "rtog::OccupancyMap::assignCells: ";

/// Each brick's pieces made contiguous, bricks in the order they first appear (a stable counting
/// sort, done only if some brick's pieces are apart), then checked disjoint brick by brick.
void groupAndCheck(std::vector<AssignedPiece>& pieces) {
  detail::FlatHashMap64 run_of;  // brick -> the index of its first run
  std::vector<std::uint32_t> run_group;  // per run: its brick's group
  std::uint32_t groups = 0;
  bool apart = false;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (i > 0 && pieces[i].brick == pieces[i - 1].brick) continue;
    const std::uint32_t at = run_of.findOrInsert(packKey(pieces[i].brick), groups);
    if (at == groups) {
      ++groups;
    } else {
      apart = true;
    }
    run_group.push_back(at);
  }
  if (apart) {
    std::vector<std::size_t> start(groups + 1, 0);
    std::vector<std::uint32_t> group_of(pieces.size());
    for (std::size_t i = 0, run = 0; i < pieces.size(); ++i) {
      if (i > 0 && !(pieces[i].brick == pieces[i - 1].brick)) ++run;
      group_of[i] = run_group[run];
      ++start[group_of[i] + 1];
    }
    for (std::size_t g = 0; g < groups; ++g) start[g + 1] += start[g];
    std::vector<AssignedPiece> grouped(pieces.size());
    for (std::size_t i = 0; i < pieces.size(); ++i) grouped[start[group_of[i]]++] = pieces[i];
    pieces.swap(grouped);
  }
  BrickMask painted{};
  for (std::size_t first = 0; first < pieces.size();) {
    std::size_t last = first;
    painted.fill(0);
    for (; last < pieces.size() && pieces[last].brick == pieces[first].brick; ++last)
      pieces[last].leaf.forEachCell([&](int c) {
        const std::uint64_t bit = std::uint64_t{1} << (c & 63);
        if (painted[static_cast<std::size_t>(c >> 6)] & bit)
          throw std::invalid_argument(std::string(kWhat) + "boxes overlap in brick " + toString(pieces[first].brick));
        painted[static_cast<std::size_t>(c >> 6)] |= bit;
      });
    first = last;
  }
}

}  // namespace

UpdateSet CellAssignment::trace(const Box* boxes, const float* values, std::size_t n) {
  const LogOddsModel& model = ctx_.store.model;
  const std::string what = kWhat;
  std::vector<AssignedPiece>& pieces = ctx_.scratch.assigned;
  pieces.clear();
  std::int64_t total_pieces = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Box& b = boxes[i];
    if (b.isEmpty() || !keyInRange(b.min) || !keyInRange(b.max))
      throw std::invalid_argument(what + "box " + std::to_string(i) + " " + toString(b) + " is empty or beyond the key range");
    if (!(values[i] >= model.clampMin() && values[i] <= model.clampMax()))
      throw std::invalid_argument(what + "value " + std::to_string(i) + " is not finite or lies outside the clamping bounds");
    const Key b0 = brickOf(b.min), b1 = brickOf(b.max);
    // A piece per brick: a box of the whole key range would be 2^33 of them.
    constexpr std::int64_t kMaxPieces = std::int64_t{1} << 26;
    total_pieces += std::int64_t(b1.x - b0.x + 1) * (b1.y - b0.y + 1) * (b1.z - b0.z + 1);
    if (total_pieces > kMaxPieces)
      throw std::invalid_argument(what + "the boxes span more than " + std::to_string(kMaxPieces) + " bricks");
    for (std::int32_t bz = b0.z; bz <= b1.z; ++bz)
      for (std::int32_t by = b0.y; by <= b1.y; ++by)
        for (std::int32_t bx = b0.x; bx <= b1.x; ++bx) {
          const Key brick{bx, by, bz}, o = brickOrigin(brick);
          AssignedPiece p{brick, LeafEntry{}};
          for (int a = 0; a < 3; ++a) {
            p.leaf.lo[a] = static_cast<std::uint8_t>(std::max(b.min[a], o[a]) - o[a]);
            p.leaf.hi[a] = static_cast<std::uint8_t>(std::min(b.max[a], o[a] + kBrickSize - 1) - o[a]);
          }
          p.leaf.value = values[i];
          pieces.push_back(p);
        }
  }
  return tracePieces();
}

UpdateSet CellAssignment::tracePieces() {
  groupAndCheck(ctx_.scratch.assigned);
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Assigned, {});
  set.assigned = &ctx_.scratch.assigned;
  return set;
}

}  // namespace rtog
