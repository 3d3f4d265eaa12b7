// An R-tree over integer boxes (Guttman 1984, quadratic split; STR bulk load).
//
// Entries are (Box, Payload) pairs addressed by stable handles, so that other indexes can
// refer to an entry while the tree moves it between nodes. Build parameters (node
// capacities) are fixed at construction; queries take their own arguments.
#pragma once

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"

namespace rtog {

using Handle = std::uint32_t;
constexpr Handle kNoHandle = std::numeric_limits<Handle>::max();

struct RTreeParams {
  std::uint32_t max_entries = 16;  ///< Node capacity M. (Default: 16)
  std::uint32_t min_entries = 6;   ///< Minimum fill m of a non-root node, 2 <= m <= M/2. (Default: 6)

  void validate() const {
    if (max_entries < 4 || max_entries > 256)
      throw std::invalid_argument("RTreeParams: max_entries must be in [4, 256]");
    if (min_entries < 2 || min_entries > max_entries / 2)
      throw std::invalid_argument("RTreeParams: min_entries must be in [2, max_entries/2]");
  }
};

/// Squared distance from a point (continuous lattice coordinates) to the volume covered by
/// a box of cells, [min, max+1) per axis.
inline double squaredDistance(const Eigen::Vector3d& p, const Box& b) {
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = b.min[a], hi = double(b.max[a]) + 1.0;
    const double d = p[a] < lo ? lo - p[a] : (p[a] > hi ? p[a] - hi : 0.0);
    d2 += d * d;
  }
  return d2;
}

/// Slab test of the segment origin + t*dir, t in [0, t_max], against a box of cells.
/// On a hit, [t_enter, t_exit] is the parameter interval inside the box.
inline bool intersectRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max, const Box& b,
                         double& t_enter, double& t_exit) {
  double t0 = 0.0, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    const double lo = b.min[a], hi = double(b.max[a]) + 1.0;
    if (dir[a] == 0.0) {
      if (origin[a] < lo || origin[a] >= hi) return false;
      continue;
    }
    const double inv = 1.0 / dir[a];
    double ta = (lo - origin[a]) * inv, tb = (hi - origin[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  t_enter = t0;
  t_exit = t1;
  return true;
}

template <class Payload>
class RTree {
 public:
  struct Hit {
    Handle handle = kNoHandle;
    double value = std::numeric_limits<double>::infinity();  ///< distance^2 (nearest) or t (ray)
    explicit operator bool() const { return handle != kNoHandle; }
  };

  explicit RTree(RTreeParams params = {}) : params_(params) {
    params_.validate();
    clear();
  }

  const RTreeParams& params() const { return params_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Number of levels (1 for a tree that is only a leaf node).
  int height() const { return level_[root_] + 1; }
  std::size_t nodeCount() const { return level_.size() - free_nodes_.size(); }

  void clear() {
    level_.clear(), count_.clear(), parent_.clear(), boxes_.clear(), ids_.clear(), free_nodes_.clear();
    loc_.clear(), payload_.clear(), free_handles_.clear();
    size_ = 0;
    root_ = allocNode(0);
    hint_leaf_ = root_;
  }

  /// Smallest box containing every entry (Box::empty() for an empty tree).
  Box bounds() const { return nodeBox(root_); }

  bool valid(Handle h) const { return h < loc_.size() && loc_[h].node != kNoNode; }
  const Box& box(Handle h) const { return boxes_[slotIndex(loc_[h].node, loc_[h].slot)]; }
  Payload& payload(Handle h) { return payload_[h]; }
  const Payload& payload(Handle h) const { return payload_[h]; }

  Handle insert(const Box& b, Payload p) {
    if (b.isEmpty()) throw std::invalid_argument("RTree::insert: empty box");
    const Handle h = allocHandle(std::move(p));
    insertEntry(b, h, 0);
    ++size_;
    return h;
  }

  void remove(Handle h) {
    if (!valid(h)) throw std::invalid_argument("RTree::remove: invalid handle");
    const Loc l = loc_[h];
    eraseSlot(l.node, l.slot);
    loc_[h].node = kNoNode;
    payload_[h] = Payload{};
    free_handles_.push_back(h);
    --size_;
    condense(l.node);
  }

  /// Changes an entry's box. Growing in place keeps the entry where it is.
  void updateBox(Handle h, const Box& b) {
    if (!valid(h)) throw std::invalid_argument("RTree::updateBox: invalid handle");
    const Loc l = loc_[h];
    Box& cur = boxes_[slotIndex(l.node, l.slot)];
    if (b.contains(cur)) {
      cur = b;
      growAncestors(l.node, b);
      return;
    }
    eraseSlot(l.node, l.slot);
    condense(l.node);
    insertEntry(b, h, 0);
  }

  /// How bulkLoad() groups entries into nodes.
  enum class Packing {
    SortTileRecursive,  ///< three nested sorts per level: the better tree
    Morton,             ///< one sort by the Morton code of box centres, then runs of M: cheaper
    AsGiven,            ///< runs of M in the order given, for entries already in spatial order
  };

  /// Runs fn(begin, end) over ranges that split [0, count), in any order and on any threads.
  using RangeRunner = std::function<void(std::size_t count, const std::function<void(std::size_t, std::size_t)>& fn)>;

  /// Replaces the contents by a packed tree. Handles are 0..n-1 in the order of `items`.
  /// With Packing::AsGiven the leaf level is filled through `for_ranges`, if given (the tree
  /// is the same for any split); the tree itself starts no threads.
  void bulkLoad(std::vector<std::pair<Box, Payload>> items, Packing packing = Packing::SortTileRecursive,
                const RangeRunner& for_ranges = {});

  /// Visits every entry whose box intersects `query`: visitor(handle, box) -> void or bool
  /// (false stops the search).
  template <class Visitor>
  void queryBox(const Box& query, Visitor&& visitor) const;

  /// The entry containing a cell, or kNoHandle (entries are expected to be disjoint; with
  /// overlapping entries, one of them).
  Handle queryPoint(const Key& k) const {
    Handle found = kNoHandle;
    queryBox(Box::cell(k), [&](Handle h, const Box&) {
      found = h;
      return false;
    });
    return found;
  }

  /// Visits entries crossed by the segment origin + t*dir, t in [0, t_max] (continuous
  /// lattice coordinates): visitor(handle, box, t_enter, t_exit) -> void or bool.
  template <class Visitor>
  void queryRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max, Visitor&& visitor) const;

  /// First entry along the segment (smallest t_enter) accepted by pred(handle, box).
  template <class Pred>
  Hit firstAlongRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max, Pred&& pred) const {
    return bestFirst(
        [&](const Box& b) {
          double t0, t1;
          return intersectRay(origin, dir, t_max, b, t0, t1) ? t0 : std::numeric_limits<double>::infinity();
        },
        pred, std::numeric_limits<double>::infinity());
  }

  /// Entry nearest to p (continuous lattice coordinates) accepted by pred(handle, box), no
  /// farther than sqrt(max_sq_dist). Hit::value is the squared distance to the box.
  template <class Pred>
  Hit nearest(const Eigen::Vector3d& p, Pred&& pred,
              double max_sq_dist = std::numeric_limits<double>::infinity()) const {
    return bestFirst([&](const Box& b) { return squaredDistance(p, b); }, pred, max_sq_dist);
  }

  /// Visits every entry: visitor(handle, box) -> void or bool.
  template <class Visitor>
  void forEach(Visitor&& visitor) const {
    for (Handle h = 0; h < loc_.size(); ++h)
      if (loc_[h].node != kNoNode && !call(visitor, h, box(h))) return;
  }

  /// Bytes held by the tree's arrays (capacity, not size).
  std::size_t memoryBytes() const {
    return level_.capacity() * sizeof(std::uint16_t) + count_.capacity() * sizeof(std::uint16_t) +
           parent_.capacity() * sizeof(std::uint32_t) + boxes_.capacity() * sizeof(Box) +
           ids_.capacity() * sizeof(std::uint32_t) + free_nodes_.capacity() * sizeof(std::uint32_t) +
           loc_.capacity() * sizeof(Loc) + payload_.capacity() * sizeof(Payload) +
           free_handles_.capacity() * sizeof(Handle);
  }

  /// Empty when the structure is sound; otherwise the first violation found. Checks:
  /// node boxes are the tight union of their children, fill limits, all leaves at level 0
  /// (balanced), parent links and handle locations, entry count, and (optionally) that no
  /// two entries intersect.
  std::string checkInvariants(bool require_disjoint_entries = true) const;

 private:
  static constexpr std::uint32_t kNoNode = std::numeric_limits<std::uint32_t>::max();
  struct Loc {
    std::uint32_t node = kNoNode;
    std::uint32_t slot = 0;
  };
  struct Entry {
    Box box;
    std::uint32_t id;  // child node (inner) or handle (leaf level)
  };

  template <class V, class... Args>
  static bool call(V& v, Args&&... args) {
    if constexpr (std::is_same_v<std::invoke_result_t<V&, Args...>, bool>) {
      return v(std::forward<Args>(args)...);
    } else {
      v(std::forward<Args>(args)...);
      return true;
    }
  }

  static double volume(const Box& b) {
    return double(b.extent(0)) * double(b.extent(1)) * double(b.extent(2));
  }

  std::size_t slotIndex(std::uint32_t node, std::uint32_t slot) const {
    return std::size_t{node} * (params_.max_entries + 1) + slot;
  }

  std::uint32_t allocNode(std::uint16_t level) {
    std::uint32_t n;
    if (!free_nodes_.empty()) {
      n = free_nodes_.back();
      free_nodes_.pop_back();
      level_[n] = level, count_[n] = 0, parent_[n] = kNoNode;
    } else {
      n = static_cast<std::uint32_t>(level_.size());
      level_.push_back(level), count_.push_back(0), parent_.push_back(kNoNode);
      boxes_.resize(boxes_.size() + params_.max_entries + 1);
      ids_.resize(ids_.size() + params_.max_entries + 1);
    }
    return n;
  }
  void freeNode(std::uint32_t n) {
    count_[n] = 0;
    parent_[n] = kNoNode;
    free_nodes_.push_back(n);
    if (hint_leaf_ == n) hint_leaf_ = kNoNode;
  }

  Handle allocHandle(Payload&& p) {
    if (!free_handles_.empty()) {
      const Handle h = free_handles_.back();
      free_handles_.pop_back();
      payload_[h] = std::move(p);
      return h;
    }
    if (loc_.size() >= kNoHandle) throw std::length_error("RTree: too many entries");
    loc_.push_back(Loc{});
    payload_.push_back(std::move(p));
    return static_cast<Handle>(loc_.size() - 1);
  }

  Box nodeBox(std::uint32_t n) const {
    if (parent_[n] == kNoNode) return computeNodeBox(n);
    return boxes_[slotIndex(parent_[n], slotInParent(n))];
  }
  Box computeNodeBox(std::uint32_t n) const {
    Box b = Box::empty();
    for (std::uint32_t i = 0; i < count_[n]; ++i) b = b.united(boxes_[slotIndex(n, i)]);
    return b;
  }
  std::uint32_t slotInParent(std::uint32_t n) const {
    const std::uint32_t p = parent_[n];
    for (std::uint32_t i = 0; i < count_[p]; ++i)
      if (ids_[slotIndex(p, i)] == n) return i;
    assert(false && "child not found in parent");
    return 0;
  }

  void appendSlot(std::uint32_t n, const Box& b, std::uint32_t id) {
    const std::uint32_t i = count_[n]++;
    boxes_[slotIndex(n, i)] = b;
    ids_[slotIndex(n, i)] = id;
    if (level_[n] == 0) {
      loc_[id] = Loc{n, i};
    } else {
      parent_[id] = n;
    }
  }
  void eraseSlot(std::uint32_t n, std::uint32_t i) {
    const std::uint32_t last = --count_[n];
    if (i != last) {
      boxes_[slotIndex(n, i)] = boxes_[slotIndex(n, last)];
      ids_[slotIndex(n, i)] = ids_[slotIndex(n, last)];
      if (level_[n] == 0) loc_[ids_[slotIndex(n, i)]].slot = i;
    }
  }

  /// Enlarges the boxes on the path above n so that they contain b.
  void growAncestors(std::uint32_t n, const Box& b) {
    while (parent_[n] != kNoNode) {
      Box& pb = boxes_[slotIndex(parent_[n], slotInParent(n))];
      if (pb.contains(b)) return;
      pb = pb.united(b);
      n = parent_[n];
    }
  }
  /// Recomputes the boxes on the path above n after a child shrank.
  void tightenAncestors(std::uint32_t n) {
    while (parent_[n] != kNoNode) {
      Box& pb = boxes_[slotIndex(parent_[n], slotInParent(n))];
      const Box nb = computeNodeBox(n);
      if (pb == nb) return;
      pb = nb;
      n = parent_[n];
    }
  }

  std::uint32_t chooseNode(const Box& b, std::uint16_t level) const;

  void insertEntry(const Box& b, std::uint32_t id, std::uint16_t level);

  /// Quadratic split of an overfull node; returns the new sibling.
  std::uint32_t split(std::uint32_t n);

  /// Guttman's CondenseTree: dissolves underfull nodes on the path up from n and
  /// re-inserts their entries at their own level.
  void condense(std::uint32_t n);

  /// Dissolves a subtree root that no longer fits under a shrunken tree.
  void reinsertSubtreeEntries(std::uint32_t node);

  template <class KeyOf, class Pred>
  Hit bestFirst(KeyOf&& key_of, Pred& pred, double limit) const;

  /// Orders entries by the Morton code of their box centres.
  static void mortonSort(std::vector<Entry>& es);

  // Where consecutive runs of M of n entries end; a short last run takes entries from the one
  // before up to the minimum fill (as fixFill() would: M >= 2m leaves that one full enough).
  // bulkLoad()'s leaf level for entries in the given order: the nodes are allocated first, then
  // threads fill ranges of them (the items, the handles' locations, the node boxes).
  void packLeafLevel(std::vector<std::pair<Box, Payload>>& items, const RangeRunner& for_ranges,
                     std::vector<Entry>& level);

  std::vector<std::size_t> runEnds(std::size_t n) const;

  /// Sort-Tile-Recursive grouping of entries into nodes of at most M entries.
  std::vector<std::vector<Entry>> strPack(std::vector<Entry> es) const;

  // Keeps every node at or above the minimum fill by borrowing from its predecessor.
  void fixFill(std::vector<std::vector<Entry>>& out) const;

  RTreeParams params_;
  // Node arrays (struct of arrays); each node owns M+1 slots so a split can see the overflow.
  std::vector<std::uint16_t> level_, count_;
  std::vector<std::uint32_t> parent_;
  std::vector<Box> boxes_;
  std::vector<std::uint32_t> ids_;
  std::vector<std::uint32_t> free_nodes_;
  // Handle table.
  std::vector<Loc> loc_;
  std::vector<Payload> payload_;
  std::vector<Handle> free_handles_;
  std::size_t size_ = 0;
  std::uint32_t root_ = 0;
  std::uint32_t hint_leaf_ = kNoNode;
};

}  // namespace rtog

#include "rtog/core/rtree_build.hpp"
#include "rtog/core/rtree_query.hpp"
