// The per-scan update set of a graded sensor model (RangeNoise): each cell a scan touched with
// its own log-odds change, the largest of the beams' (the most occupied claim wins, as occupied
// wins over free in UpdateBatch), grouped by brick in Morton order. Cells whose change is exactly
// the miss change (most of a beam: those before its band) are marked in an UpdateBatch's free
// masks, with its fast walk, and only the others one by one.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "integrate/brick_update.hpp"
#include "integrate/update_batch.hpp"
#include "rtog/core/key.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/stats.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

class GradedScan {
 public:
  void clear();
  void mark(const Key& k, float delta) {
    const auto i = static_cast<std::uint32_t>(keys_.size());
    const std::uint32_t at = index_.findOrInsert(packKey(k), i);
    if (at == i) {
      keys_.push_back(k);
      deltas_.push_back(delta);
    } else if (delta > deltas_[at]) {
      deltas_[at] = delta;
    }
  }
  /// Room for n marks.
  void reserve(std::size_t n) {
    keys_.reserve(n);
    deltas_.reserve(n);
  }
  /// mark() of a cell the caller knows is not marked yet (e.g. the cells of disjoint boxes moved
  /// one-to-one): no lookup.
  void markDistinct(const Key& k, float delta) {
    keys_.push_back(k);
    deltas_.push_back(delta);
  }
  /// Groups the marked cells by brick, bricks in Morton order, cells by local index. Ends marking.
  void finalize();
  /// Builds the finalized set directly, brick by brick, instead of mark() and finalize(): after
  /// clear(), bricks in ascending Morton code, each with its cells in ascending local index (and
  /// no miss mask).
  void appendBrick(const Key& brick, std::uint64_t code, const GradedCell* cells, std::size_t n) {
    bricks_.push_back(BrickEntry{brick, code, nullptr, static_cast<std::uint32_t>(cells_.size()),
                                 static_cast<std::uint32_t>(n)});
    cells_.insert(cells_.end(), cells, cells + n);
  }

  std::size_t brickCount() const { return bricks_.size(); }
  const Key& brick(std::size_t b) const { return bricks_[b].key; }
  /// The brick's cells of their own change, by local index.
  const GradedCell* cells(std::size_t b) const { return cells_.data() + bricks_[b].first; }
  std::size_t cellCount(std::size_t b) const { return bricks_[b].count; }
  /// The brick's cells of the miss change (a cell may be in cells() too: the larger change
  /// counts), or nullptr.
  const BrickMask* missMask(std::size_t b) const { return bricks_[b].miss; }
  /// The brick's Morton code (ascending with b).
  std::uint64_t brickCode(std::size_t b) const { return bricks_[b].code; }
  std::size_t memoryBytes() const;

  /// Traces a scan's beams with the range-noise rule into this set (no change to the map): the
  /// same beams as the beam model are skipped or cut; a no-return beam frees the cells before its
  /// end, as in the beam model. Throws std::out_of_range if the origin has no key.
  void traceRangeNoise(const Lattice& lattice, const LogOddsModel& model, const Eigen::Vector3d& origin,
                       const Eigen::Vector3f* points, std::size_t count, const InsertParams& ip,
                       const std::uint8_t* is_hit, InsertStats& stats);

 private:
  struct BrickEntry {
    Key key;
    std::uint64_t code;
    const BrickMask* miss;
    std::uint32_t first, count;
  };
  UpdateBatch miss_;             // cells of exactly the miss change
  detail::FlatHashMap64 index_;  // packed key -> position in keys_ / deltas_
  std::vector<Key> keys_;
  std::vector<float> deltas_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> order_;  // finalize(): brick's Morton code, local << 32 | position
  std::vector<BrickEntry> bricks_;
  std::vector<std::uint64_t> codes_;  // finalize(): the graded bricks' Morton codes
  std::vector<GradedCell> cells_;
};

}  // namespace rtog
