#include "integrate/cell_assignment.hpp"

#include <stdexcept>
#include <string>
#include <vector>

#include "integrate/insert_scratch.hpp"
#include "storage/map_store.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

UpdateSet CellAssignment::trace(const Box* boxes, const float* values, std::size_t n) {
  const LogOddsModel& model = ctx_.store.model;
  const std::string what = "rtog::OccupancyMap::assignCells: ";
  // Each box cut into its bricks' pieces; the pieces grouped by brick, bricks in the order they
  // first appear (so a map without leaves takes its bricks in the caller's order, as read() does).
  detail::FlatHashMap64 group_of;
  std::vector<Key> bricks;
  std::vector<std::pair<std::uint32_t, AssignedPiece>> pieces;
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
          const auto g = static_cast<std::uint32_t>(bricks.size());
          const std::uint32_t at = group_of.findOrInsert(packKey(brick), g);
          if (at == g) bricks.push_back(brick);
          AssignedPiece p{brick, LeafEntry{}};
          for (int a = 0; a < 3; ++a) {
            p.leaf.lo[a] = static_cast<std::uint8_t>(std::max(b.min[a], o[a]) - o[a]);
            p.leaf.hi[a] = static_cast<std::uint8_t>(std::min(b.max[a], o[a] + kBrickSize - 1) - o[a]);
          }
          p.leaf.value = values[i];
          pieces.emplace_back(at, p);
        }
  }
  // Grouped (stable), then each brick's pieces checked for overlap before anything changes.
  std::vector<std::size_t> start(bricks.size() + 1, 0);
  for (const auto& [g, p] : pieces) ++start[g + 1];
  for (std::size_t g = 0; g < bricks.size(); ++g) start[g + 1] += start[g];
  std::vector<AssignedPiece>& out = ctx_.scratch.assigned;
  out.resize(pieces.size());
  for (const auto& [g, p] : pieces) out[start[g]++] = p;
  BrickMask painted{};
  for (std::size_t first = 0; first < out.size();) {
    std::size_t last = first;
    painted.fill(0);
    for (; last < out.size() && out[last].brick == out[first].brick; ++last)
      out[last].leaf.forEachCell([&](int c) {
        const std::uint64_t bit = std::uint64_t{1} << (c & 63);
        if (painted[static_cast<std::size_t>(c >> 6)] & bit)
          throw std::invalid_argument(what + "boxes overlap in brick " + toString(out[first].brick));
        painted[static_cast<std::size_t>(c >> 6)] |= bit;
      });
    first = last;
  }
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Assigned, {});
  set.assigned = &out;
  return set;
}

}  // namespace rtog
