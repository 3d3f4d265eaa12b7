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
#include <limits>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/detail/radix_sort.hpp"
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

  /// Replaces the contents by a packed tree. Handles are 0..n-1 in the order of `items`.
  /// With Packing::AsGiven, `threads` threads fill the leaf level (the tree is the same).
  void bulkLoad(std::vector<std::pair<Box, Payload>> items, Packing packing = Packing::SortTileRecursive,
                int threads = 1) {
    for (const auto& it : items)
      if (it.first.isEmpty()) throw std::invalid_argument("RTree::bulkLoad: empty box");
    clear();
    if (items.empty()) return;
    std::vector<Entry> level;
    // The nodes of a packed tree: about n / (M - 1) (fewer than that with full nodes).
    const std::size_t nodes = level_.size() + items.size() / (params_.max_entries - 1) + 8;
    level_.reserve(nodes), count_.reserve(nodes), parent_.reserve(nodes);
    boxes_.reserve(nodes * (params_.max_entries + 1)), ids_.reserve(nodes * (params_.max_entries + 1));
    size_ = items.size();
    freeNode(root_);
    std::uint16_t lvl = 0;
    if (packing == Packing::AsGiven) {
      packLeafLevel(items, std::max(threads, 1), level);
      lvl = 1;
    } else {
      level.reserve(items.size());
      payload_.reserve(items.size());
      loc_.reserve(items.size());
      for (auto& it : items) level.push_back(Entry{it.first, allocHandle(std::move(it.second))});
      if (packing == Packing::Morton) mortonSort(level);
    }
    std::vector<Entry> next;
    while (level.size() > 1 || lvl == 0) {
      next.clear();
      const auto pack = [&](const Entry* first, const Entry* last) {
        const std::uint32_t n = allocNode(lvl);
        for (const Entry* e = first; e != last; ++e) appendSlot(n, e->box, e->id);
        next.push_back(Entry{computeNodeBox(n), n});
      };
      if (packing == Packing::SortTileRecursive) {
        for (const auto& g : strPack(std::move(level))) pack(g.data(), g.data() + g.size());
      } else {
        // The order survives packing: each level's nodes come in the order of their entries.
        std::size_t begin = 0;
        for (const std::size_t end : runEnds(level.size())) {
          pack(level.data() + begin, level.data() + end);
          begin = end;
        }
      }
      level.swap(next);
      ++lvl;
    }
    root_ = level.front().id;
    parent_[root_] = kNoNode;
    hint_leaf_ = kNoNode;
  }

  /// Visits every entry whose box intersects `query`: visitor(handle, box) -> void or bool
  /// (false stops the search).
  template <class Visitor>
  void queryBox(const Box& query, Visitor&& visitor) const {
    std::vector<std::uint32_t> stack{root_};
    while (!stack.empty()) {
      const std::uint32_t n = stack.back();
      stack.pop_back();
      for (std::uint32_t i = 0; i < count_[n]; ++i) {
        const std::size_t s = slotIndex(n, i);
        if (!boxes_[s].intersects(query)) continue;
        if (level_[n] > 0) {
          stack.push_back(ids_[s]);
        } else if (!call(visitor, ids_[s], boxes_[s])) {
          return;
        }
      }
    }
  }

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
  void queryRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max, Visitor&& visitor) const {
    std::vector<std::uint32_t> stack{root_};
    double t0, t1;
    while (!stack.empty()) {
      const std::uint32_t n = stack.back();
      stack.pop_back();
      for (std::uint32_t i = 0; i < count_[n]; ++i) {
        const std::size_t s = slotIndex(n, i);
        if (!intersectRay(origin, dir, t_max, boxes_[s], t0, t1)) continue;
        if (level_[n] > 0) {
          stack.push_back(ids_[s]);
        } else if (!call(visitor, ids_[s], boxes_[s], t0, t1)) {
          return;
        }
      }
    }
  }

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
  std::string checkInvariants(bool require_disjoint_entries = true) const {
    std::ostringstream err;
    if (parent_[root_] != kNoNode) return "root has a parent";
    if (level_[root_] > 0 && count_[root_] < 2) return "inner root with fewer than 2 children";
    std::size_t entries = 0;
    std::vector<std::uint32_t> stack{root_};
    while (!stack.empty()) {
      const std::uint32_t n = stack.back();
      stack.pop_back();
      if (count_[n] > params_.max_entries) return "node over capacity";
      if (n != root_ && count_[n] < params_.min_entries) {
        err << "node " << n << " under minimum fill (" << count_[n] << ")";
        return err.str();
      }
      for (std::uint32_t i = 0; i < count_[n]; ++i) {
        const std::size_t s = slotIndex(n, i);
        if (boxes_[s].isEmpty()) return "empty box in node";
        if (level_[n] > 0) {
          const std::uint32_t c = ids_[s];
          if (parent_[c] != n) return "broken parent link";
          if (level_[c] + 1 != level_[n]) return "unbalanced: child level mismatch";
          if (computeNodeBox(c) != boxes_[s]) {
            err << "node box " << toString(boxes_[s]) << " is not the tight union of its children "
                << toString(computeNodeBox(c));
            return err.str();
          }
          stack.push_back(c);
        } else {
          const Handle h = ids_[s];
          if (h >= loc_.size() || loc_[h].node != n || loc_[h].slot != i) return "handle location mismatch";
          ++entries;
        }
      }
    }
    if (entries != size_) return "entry count mismatch";
    if (require_disjoint_entries) {
      std::string overlap;
      forEach([&](Handle h, const Box& b) {
        queryBox(b, [&](Handle g, const Box& gb) {
          if (g == h) return true;
          overlap = "entries overlap: " + toString(b) + " and " + toString(gb);
          return false;
        });
        return overlap.empty();
      });
      if (!overlap.empty()) return overlap;
    }
    return {};
  }

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

  std::uint32_t chooseNode(const Box& b, std::uint16_t level) const {
    // Spatially sorted insertions mostly land in the previous leaf; it is a valid choice
    // whenever it needs no enlargement.
    if (level == 0 && hint_leaf_ != kNoNode && level_[hint_leaf_] == 0 && count_[hint_leaf_] < params_.max_entries &&
        (parent_[hint_leaf_] != kNoNode || hint_leaf_ == root_) && nodeBox(hint_leaf_).contains(b))
      return hint_leaf_;
    std::uint32_t n = root_;
    while (level_[n] > level) {
      std::uint32_t best = 0;
      double best_enl = std::numeric_limits<double>::infinity(), best_vol = best_enl;
      for (std::uint32_t i = 0; i < count_[n]; ++i) {
        const Box& cb = boxes_[slotIndex(n, i)];
        const double v = volume(cb);
        const double enl = volume(cb.united(b)) - v;
        if (enl < best_enl || (enl == best_enl && v < best_vol)) best = i, best_enl = enl, best_vol = v;
      }
      n = ids_[slotIndex(n, best)];
    }
    return n;
  }

  void insertEntry(const Box& b, std::uint32_t id, std::uint16_t level) {
    std::uint32_t n = chooseNode(b, level);
    appendSlot(n, b, id);
    if (level == 0) hint_leaf_ = n;
    growAncestors(n, b);
    while (count_[n] > params_.max_entries) {
      const std::uint32_t sibling = split(n);
      if (parent_[n] == kNoNode) {
        const std::uint32_t r = allocNode(static_cast<std::uint16_t>(level_[n] + 1));
        appendSlot(r, computeNodeBox(n), n);
        appendSlot(r, computeNodeBox(sibling), sibling);
        root_ = r;
        return;
      }
      const std::uint32_t p = parent_[n];
      boxes_[slotIndex(p, slotInParent(n))] = computeNodeBox(n);
      appendSlot(p, computeNodeBox(sibling), sibling);
      n = p;
    }
  }

  /// Quadratic split of an overfull node; returns the new sibling.
  std::uint32_t split(std::uint32_t n) {
    const std::uint32_t total = count_[n];
    if (total < 2) throw std::logic_error("RTree::split: nothing to split");
    std::vector<Entry> es(total);
    for (std::uint32_t i = 0; i < total; ++i) es[i] = Entry{boxes_[slotIndex(n, i)], ids_[slotIndex(n, i)]};
    // Pick the pair that would waste the most volume together.
    std::uint32_t s1 = 0, s2 = 1;
    double worst = -std::numeric_limits<double>::infinity();
    for (std::uint32_t i = 0; i < total; ++i)
      for (std::uint32_t j = i + 1; j < total; ++j) {
        const double d = volume(es[i].box.united(es[j].box)) - volume(es[i].box) - volume(es[j].box);
        if (d > worst) worst = d, s1 = i, s2 = j;
      }
    std::vector<std::uint8_t> group(total, 2);
    group[s1] = 0, group[s2] = 1;
    Box gb[2] = {es[s1].box, es[s2].box};
    std::uint32_t gcount[2] = {1, 1};
    std::uint32_t remaining = total - 2;
    const std::uint32_t m = params_.min_entries;
    while (remaining > 0) {
      int forced = -1;
      if (gcount[0] + remaining == m) forced = 0;
      if (gcount[1] + remaining == m) forced = 1;
      std::uint32_t pick = 0;
      double best_diff = -1.0, d0b = 0.0, d1b = 0.0;
      for (std::uint32_t i = 0; i < total; ++i) {
        if (group[i] != 2) continue;
        const double d0 = volume(gb[0].united(es[i].box)) - volume(gb[0]);
        const double d1 = volume(gb[1].united(es[i].box)) - volume(gb[1]);
        const double diff = std::abs(d0 - d1);
        if (diff > best_diff) best_diff = diff, pick = i, d0b = d0, d1b = d1;
      }
      int g;
      if (forced >= 0) {
        g = forced;
      } else if (d0b != d1b) {
        g = d0b < d1b ? 0 : 1;
      } else if (volume(gb[0]) != volume(gb[1])) {
        g = volume(gb[0]) < volume(gb[1]) ? 0 : 1;
      } else {
        g = gcount[0] <= gcount[1] ? 0 : 1;
      }
      group[pick] = static_cast<std::uint8_t>(g);
      gb[g] = gb[g].united(es[pick].box);
      ++gcount[g];
      --remaining;
    }
    const std::uint32_t sibling = allocNode(level_[n]);
    count_[n] = 0;
    for (std::uint32_t i = 0; i < total; ++i) appendSlot(group[i] == 0 ? n : sibling, es[i].box, es[i].id);
    return sibling;
  }

  /// Guttman's CondenseTree: dissolves underfull nodes on the path up from n and
  /// re-inserts their entries at their own level.
  void condense(std::uint32_t n) {
    std::vector<std::pair<Entry, std::uint16_t>> orphans;
    while (parent_[n] != kNoNode) {
      const std::uint32_t p = parent_[n];
      if (count_[n] < params_.min_entries) {
        eraseSlot(p, slotInParent(n));
        for (std::uint32_t i = 0; i < count_[n]; ++i)
          orphans.push_back({Entry{boxes_[slotIndex(n, i)], ids_[slotIndex(n, i)]}, level_[n]});
        freeNode(n);
      } else {
        boxes_[slotIndex(p, slotInParent(n))] = computeNodeBox(n);
      }
      n = p;
    }
    // Shorten the tree while the root is an inner node with a single child.
    while (level_[root_] > 0 && count_[root_] == 1) {
      const std::uint32_t child = ids_[slotIndex(root_, 0)];
      freeNode(root_);
      root_ = child;
      parent_[root_] = kNoNode;
    }
    if (level_[root_] > 0 && count_[root_] == 0) {  // everything below was dissolved
      level_[root_] = 0;
    }
    // Re-insert higher levels first so that lower-level orphans find their level.
    std::stable_sort(orphans.begin(), orphans.end(),
                     [](const auto& a, const auto& b) { return a.second > b.second; });
    for (const auto& [e, lvl] : orphans) {
      if (lvl > level_[root_]) {
        // The tree shrank below this subtree's level: re-insert its leaf entries instead.
        reinsertSubtreeEntries(e.id);
      } else {
        insertEntry(e.box, e.id, lvl);
      }
    }
  }

  /// Dissolves a subtree root that no longer fits under a shrunken tree.
  void reinsertSubtreeEntries(std::uint32_t node) {
    std::vector<std::pair<Entry, std::uint16_t>> es;
    for (std::uint32_t i = 0; i < count_[node]; ++i)
      es.push_back({Entry{boxes_[slotIndex(node, i)], ids_[slotIndex(node, i)]}, level_[node]});
    freeNode(node);
    for (const auto& [e, lvl] : es) {
      if (lvl > level_[root_]) {
        reinsertSubtreeEntries(e.id);
      } else {
        insertEntry(e.box, e.id, lvl);
      }
    }
  }

  template <class KeyOf, class Pred>
  Hit bestFirst(KeyOf&& key_of, Pred& pred, double limit) const {
    using Item = std::pair<double, std::uint64_t>;  // (key, node or handle | leaf flag)
    constexpr std::uint64_t kIsEntry = std::uint64_t{1} << 63;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    queue.push({0.0, root_});
    while (!queue.empty()) {
      const auto [k, item] = queue.top();
      queue.pop();
      if (k > limit) break;
      if (item & kIsEntry) {
        const Handle h = static_cast<Handle>(item & ~kIsEntry);
        if (pred(h, box(h))) return Hit{h, k};
        continue;
      }
      const auto n = static_cast<std::uint32_t>(item);
      for (std::uint32_t i = 0; i < count_[n]; ++i) {
        const std::size_t s = slotIndex(n, i);
        const double kk = key_of(boxes_[s]);
        if (!std::isfinite(kk) || kk > limit) continue;
        queue.push({kk, level_[n] > 0 ? std::uint64_t{ids_[s]} : (std::uint64_t{ids_[s]} | kIsEntry)});
      }
    }
    return Hit{};
  }

  /// Orders entries by the Morton code of their box centres.
  static void mortonSort(std::vector<Entry>& es) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order(es.size());
    for (std::size_t i = 0; i < es.size(); ++i) {
      const Box& b = es[i].box;
      // Centre on the lattice, rounded down.
      const auto mid = [&](int a) { return static_cast<std::int32_t>((std::int64_t{b.min[a]} + b.max[a]) >> 1); };
      order[i] = {mortonCode(Key{mid(0), mid(1), mid(2)}), static_cast<std::uint32_t>(i)};
    }
    detail::radixSortByKey(order);
    std::vector<Entry> sorted;
    sorted.reserve(es.size());
    for (const auto& o : order) sorted.push_back(es[o.second]);
    es.swap(sorted);
  }

  // Where consecutive runs of M of n entries end; a short last run takes entries from the one
  // before up to the minimum fill (as fixFill() would: M >= 2m leaves that one full enough).
  // bulkLoad()'s leaf level for entries in the given order: the nodes are allocated first, then
  // threads fill ranges of them (the items, the handles' locations, the node boxes).
  void packLeafLevel(std::vector<std::pair<Box, Payload>>& items, int threads, std::vector<Entry>& level) {
    if (items.size() >= kNoHandle) throw std::length_error("RTree: too many entries");
    const std::vector<std::size_t> ends = runEnds(items.size());
    level.resize(ends.size());
    for (Entry& e : level) e.id = allocNode(0);
    loc_.resize(items.size());
    payload_.resize(items.size());
    const auto fill = [&](std::size_t first_run, std::size_t last_run) {
      for (std::size_t r = first_run; r < last_run; ++r) {
        const std::uint32_t n = level[r].id;
        for (std::size_t i = r == 0 ? 0 : ends[r - 1]; i < ends[r]; ++i) {
          payload_[i] = std::move(items[i].second);
          appendSlot(n, items[i].first, static_cast<std::uint32_t>(i));
        }
        level[r].box = computeNodeBox(n);
      }
    };
    // Below some thousand nodes a thread costs more than it saves.
    const std::size_t parts = std::min<std::size_t>(static_cast<std::size_t>(threads), 1 + ends.size() / 1024);
    std::vector<std::thread> workers;
    for (std::size_t p = 1; p < parts; ++p)
      workers.emplace_back(fill, ends.size() * p / parts, ends.size() * (p + 1) / parts);
    fill(0, ends.size() / parts);
    for (auto& w : workers) w.join();
  }

  std::vector<std::size_t> runEnds(std::size_t n) const {
    const std::size_t M = params_.max_entries, m = params_.min_entries;
    std::vector<std::size_t> ends;
    for (std::size_t k = M; k < n + M; k += M) ends.push_back(std::min(n, k));
    if (ends.size() > 1) {
      const std::size_t last = n - ends[ends.size() - 2];
      if (last < m) ends[ends.size() - 2] -= m - last;
    }
    return ends;
  }

  /// Sort-Tile-Recursive grouping of entries into nodes of at most M entries.
  std::vector<std::vector<Entry>> strPack(std::vector<Entry> es) const {
    const std::size_t M = params_.max_entries;
    const std::size_t nodes = (es.size() + M - 1) / M;
    const auto center = [](const Entry& e, int a) { return double(e.box.min[a]) + double(e.box.max[a]); };
    const std::size_t slabs = static_cast<std::size_t>(std::ceil(std::cbrt(double(nodes))));
    std::sort(es.begin(), es.end(), [&](const Entry& a, const Entry& b) { return center(a, 0) < center(b, 0); });
    std::vector<std::vector<Entry>> out;
    const std::size_t per_slab_x = slabs * slabs * M;
    for (std::size_t i = 0; i < es.size(); i += per_slab_x) {
      const std::size_t ie = std::min(es.size(), i + per_slab_x);
      std::sort(es.begin() + i, es.begin() + ie,
                [&](const Entry& a, const Entry& b) { return center(a, 1) < center(b, 1); });
      const std::size_t per_slab_y = slabs * M;
      for (std::size_t j = i; j < ie; j += per_slab_y) {
        const std::size_t je = std::min(ie, j + per_slab_y);
        std::sort(es.begin() + j, es.begin() + je,
                  [&](const Entry& a, const Entry& b) { return center(a, 2) < center(b, 2); });
        for (std::size_t k = j; k < je; k += M)
          out.emplace_back(es.begin() + k, es.begin() + std::min(je, k + M));
      }
    }
    fixFill(out);
    return out;
  }

  // Keeps every node at or above the minimum fill by borrowing from its predecessor.
  void fixFill(std::vector<std::vector<Entry>>& out) const {
    const std::size_t M = params_.max_entries;
    for (std::size_t g = 1; g < out.size(); ++g) {
      while (out[g].size() < params_.min_entries && out[g - 1].size() > params_.min_entries) {
        out[g].insert(out[g].begin(), out[g - 1].back());
        out[g - 1].pop_back();
      }
    }
    if (out.size() > 1 && out.back().size() < params_.min_entries) {
      // Fold a short tail into its predecessor and re-split evenly.
      auto tail = std::move(out.back());
      out.pop_back();
      auto& prev = out.back();
      prev.insert(prev.end(), tail.begin(), tail.end());
      if (prev.size() > M) {
        std::vector<Entry> second(prev.begin() + prev.size() / 2, prev.end());
        prev.resize(prev.size() / 2);
        out.push_back(std::move(second));
      }
    }
  }

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
