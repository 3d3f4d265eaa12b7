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
#include "storage/brick.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog {

/// The end cells of a scan's returned beams, and which of them share one band (InsertParams::
/// range_noise_shared_band): counted over the whole scan before it is traced, so that which
/// beams share does not depend on how the beams are split among threads. Each returned beam's
/// end cell is kept, so that the trace classifies only the others.
class SharedEnds {
 public:
  static constexpr std::uint32_t kNone = detail::FlatHashMap64::kAbsent;
  /// Counts the scan's beams by end cell; with range_noise_shared_band 0 counts nothing (every
  /// beam kNone, a band each).
  void count(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points, std::size_t n,
             const InsertParams& ip, const std::uint8_t* is_hit);
  /// The end cell's group of returned beam i of the scan, or kNone (not returned, or not counted).
  std::uint32_t group(std::size_t i) const { return i < group_of_.size() ? group_of_[i] : kNone; }
  std::size_t groups() const { return ends_.size(); }
  const Key& end(std::uint32_t g) const { return ends_[g]; }
  /// True if the group's cell is the end of at least range_noise_shared_band beams.
  bool shared(std::uint32_t g) const { return beams_[g] >= min_beams_; }
  std::size_t memoryBytes() const {
    return index_.memoryBytes() + ends_.capacity() * sizeof(Key) +
           (beams_.capacity() + group_of_.capacity()) * sizeof(std::uint32_t);
  }

 private:
  detail::FlatHashMap64 index_;  // packed end key -> group
  std::vector<Key> ends_;        // by group
  std::vector<std::uint32_t> beams_, group_of_;  // by group: beams; by beam: group
  std::uint32_t min_beams_ = 0;
};

class GradedScan {
 public:
  void clear();
  /// A change of cell k; a cell marked several times takes the largest.
  void mark(const Key& k, float delta) {
    const Key b = brickOf(k);
    if (last_slot_ == kNoSlot || !(b == last_brick_)) enterBrick(b);
    marks_[last_slot_].push_back(Mark{static_cast<std::uint16_t>(localIndex(k)), delta});
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
  /// end, as in the beam model. A beam ending in a cell of `shared_ends` frees the cells before
  /// its own band, and the cell's one band is graded once, along the ray to its centre.
  /// `shared_ends`: the whole scan's when these points are a part of it, its beams `first`
  /// on; null when they are the whole scan (counted here). Throws std::out_of_range if the
  /// origin has no key.
  void traceRangeNoise(const Lattice& lattice, const LogOddsModel& model, const Eigen::Vector3d& origin,
                       const Eigen::Vector3f* points, std::size_t count, const InsertParams& ip,
                       const std::uint8_t* is_hit, const SharedEnds* shared_ends, std::size_t first,
                       InsertStats& stats);

 private:
  struct BrickEntry {
    Key key;
    std::uint64_t code;
    const BrickMask* miss;
    std::uint32_t first, count;
  };
  struct Mark {
    std::uint16_t local;
    float delta;
  };
  static constexpr std::uint32_t kNoSlot = detail::FlatHashMap64::kAbsent;
  /// Makes `brick`'s slot the one mark() appends to.
  void enterBrick(const Key& brick);

  UpdateBatch miss_;  // cells of exactly the miss change
  // The marks, by brick in the order made: a band's cells follow each other within a brick, so
  // a mark is an append to the last brick's list; finalize() takes each cell's largest.
  std::vector<std::vector<Mark>> marks_;  // by slot (the lists kept between scans)
  std::vector<Key> slot_bricks_;          // by slot
  detail::FlatHashMap64 slots_;           // packed brick key -> slot
  Key last_brick_{};
  std::uint32_t last_slot_ = kNoSlot;
  std::vector<std::uint8_t> banded_;  // traceRangeNoise(): by SharedEnds group, its band traced
  SharedEnds own_ends_;           // traceRangeNoise() of a whole scan
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order_;  // finalize(): the bricks' Morton codes, slots
  std::vector<float> value_;                                     // finalize(): one brick's cells' largest marks
  std::vector<BrickEntry> bricks_;
  std::vector<std::uint64_t> codes_;  // finalize(): the graded bricks' Morton codes
  std::vector<GradedCell> cells_;
};

}  // namespace rtog
