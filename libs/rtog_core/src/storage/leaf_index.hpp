// The leaf level of the map and its index: the bricks with their leaves, the brick hash, and
// the upper R-tree over the leaf nodes.
//
// Copies share: each brick, the array of the bricks' pointers, the brick hash and the upper tree
// (with the leaf nodes' handles) are copy-on-write objects, so a copy of the index costs a few
// pointers, and a write clones what it touches first: the array (once after a copy, before any
// applier runs: unshareBricks()), the bricks it changes (mutableBrick()), the hash or the tree on
// their first change.
//
// The R-tree's leaf level is clustered by brick: a brick's cuboids (in Morton order of their
// first cell when packed; later updates append and fill holes from the end) are cut into leaf
// nodes of at most M consecutive entries. The levels above are a Guttman R-tree over the leaf
// nodes' boxes. A brick's array is thus the storage of its leaf nodes, and the brick hash finds
// a cell's leaf without descending the tree.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rtog/core/log_odds.hpp"
#include "rtog/core/rtree.hpp"
#include "storage/brick.hpp"
#include "util/cow_ptr.hpp"
#include "util/flat_hash_map.hpp"
#include "util/small_vector.hpp"

namespace rtog {

/// One leaf: a brick-local box and its log-odds, 12 bytes.
struct LeafEntry : LocalBox {
  float value;
};
inline LeafEntry makeLeaf(const std::uint8_t lo[3], const std::uint8_t hi[3], float value) {
  LeafEntry e;
  for (int a = 0; a < 3; ++a) e.lo[a] = lo[a], e.hi[a] = hi[a];
  e.value = value;
  return e;
}
/// makeLeaf() appended to `out`, written in place: a leaf made on the stack and copied is read
/// back whole from its bytes just written, which stalls the covers that emit leaves by the million.
inline void appendLeaf(std::vector<LeafEntry>& out, const std::uint8_t lo[3], const std::uint8_t hi[3], float value) {
  LeafEntry& e = out.emplace_back();
  for (int a = 0; a < 3; ++a) e.lo[a] = lo[a], e.hi[a] = hi[a];
  e.value = value;
}
/// A leaf merged away, until the brick's array is compacted: lo[0] == kDead.
constexpr std::uint8_t kDead = 0xFF;

struct LeafNodeRef {
  std::uint32_t brick;  // slot in the brick array
  std::uint32_t node;   // leaf node index within the brick
};

struct Brick {
  Key brick;
  std::vector<LeafEntry> leaves;
};

/// The upper tree and, per brick slot, the tree's handle of each of its leaf nodes: one object,
/// shared between copies until either changes.
struct UpperTree {
  explicit UpperTree(const RTreeParams& params = {}) : tree(params) {}
  RTree<LeafNodeRef> tree;
  std::vector<detail::SmallVector<Handle, 4>> nodes;
};

class LeafIndex {
 public:
  explicit LeafIndex(const RTreeParams& params) : upper_(UpperTree(params)) {}

  void clear();
  /// The slot of a brick, made (without leaves) if new. Slots are stable: bricks are never removed.
  std::uint32_t brickSlot(const Key& brick);
  const Brick* findBrick(const Key& brick) const;
  const LeafEntry* findLeaf(const Key& k) const;
  const Brick& brick(std::uint32_t slot) const { return *(*bricks_)[slot]; }
  /// Makes this index's array of brick pointers its own (cloned if a copy shares it): called
  /// before appliers run, so that their mutableBrick() calls on several threads only read it.
  void unshareBricks() { bricks_.write(); }
  /// The brick for writing: cloned first if a copy of the map shares it. Appliers on several
  /// threads may call it for distinct slots at once, after unshareBricks().
  Brick& mutableBrick(std::uint32_t slot) { return bricks_.write()[slot].write(); }
  std::size_t brickCount() const { return bricks_->size(); }
  /// Calls fn(const Brick&) for every brick in slot order.
  template <class Fn>
  void forEachBrick(Fn&& fn) const {
    for (const auto& b : *bricks_) fn(*b);
  }
  /// How many bricks this index shares with copies of it.
  std::size_t sharedBricks() const;
  /// Room for `more` new bricks: the array must not move while appliers hold bricks.
  void reserveBricks(std::size_t more);

  std::size_t leafCount() const { return leaf_count_; }
  void addLeafCount(std::int64_t delta) {
    leaf_count_ = static_cast<std::size_t>(static_cast<std::int64_t>(leaf_count_) + delta);
  }
  const RTree<LeafNodeRef>& upper() const { return upper_->tree; }

  std::size_t leafNodeSize() const { return upper_->tree.params().max_entries; }
  std::size_t leafNodeCount(const Brick& b) const { return (b.leaves.size() + leafNodeSize() - 1) / leafNodeSize(); }
  Box leafNodeBox(const Brick& b, std::size_t node) const;
  /// The union of a leaf node's entries in brick-local cells.
  LocalBox localNodeBox(const std::vector<LeafEntry>& leaves, std::size_t node) const;

  /// Brings the brick's leaf nodes in the upper tree up to date with its leaves.
  void syncLeafNodes(std::uint32_t slot);
  /// Packs every brick's leaf nodes into a fresh upper tree (Morton-order bulk load) on up to
  /// `threads` threads. boxes_of, if not empty, holds per slot the leaf-node boxes taken when
  /// the brick was reshaped (or null): read instead of every leaf again.
  void rebuildUpperTree(int threads = 1, const std::vector<const LocalBox*>& boxes_of = {});
  /// Brings the upper tree up to date with the leaf nodes of the bricks `reshaped` (sorted here),
  /// by a rebuild if they are many compared with the tree. boxes_of: as rebuildUpperTree().
  void refreshUpperTree(std::vector<std::uint32_t>& reshaped, int threads = 1,
                        const std::function<std::vector<const LocalBox*>()>& boxes_of = {});
  /// Rewrites a brick's live leaves (lo[0] != kDead) in Morton order of their first cell.
  /// `local`: brick-local cell -> leaf index or -1, naming each live leaf at least at its first cell.
  void packLeaves(std::uint32_t slot, const std::vector<std::int32_t>& local);

  /// Calls fn(box, value) for every leaf.
  template <class Fn>
  void forEachLeaf(Fn&& fn) const {
    for (const auto& p : *bricks_) {
      const Key o = brickOrigin(p->brick);
      for (const LeafEntry& e : p->leaves) fn(e.global(o), e.value);
    }
  }
  /// Calls fn(box, value) for every leaf that intersects `region`, through the R-tree.
  template <class Fn>
  void forEachLeafIn(const Box& region, Fn&& fn) const {
    upper_->tree.queryBox(region, [&](Handle h, const Box&) {
      forEachInLeafNode(h, [&](const Box& b, float v) {
        if (b.intersects(region)) fn(b, v);
      });
    });
  }
  /// Visits the leaf entries of one upper-tree item.
  template <class Fn>
  void forEachInLeafNode(Handle h, Fn&& fn) const {
    const LeafNodeRef r = upper_->tree.payload(h);
    const Brick& b = *(*bricks_)[r.brick];
    const Key o = brickOrigin(b.brick);
    const std::size_t first = r.node * leafNodeSize(), last = std::min(b.leaves.size(), first + leafNodeSize());
    for (std::size_t i = first; i < last; ++i) fn(b.leaves[i].global(o), b.leaves[i].value);
  }

  std::size_t memoryBytes() const;
  /// A lower bound of memoryBytes() in O(1) (leaves counted at their size, not capacity): for the
  /// insertion path, which must not walk every brick after every scan.
  std::size_t memoryBytesAtLeast() const {
    return upper_->tree.memoryBytes() + brick_index_->memoryBytes() + bricks_->capacity() * sizeof(BrickPtr) +
           bricks_->size() * sizeof(Brick) + leaf_count_ * sizeof(LeafEntry);
  }
  /// Empty if the R-tree, the brick index and the leaves are sound and agree; else the first
  /// problem. Leaf values must lie in the model's bounds, merged ones be `mergeable`.
  std::string checkInvariants(const LogOddsModel& model, const std::function<bool(float)>& mergeable) const;

 private:
  detail::CowPtr<UpperTree> upper_;
  detail::CowPtr<detail::FlatHashMap64> brick_index_;
  using BrickPtr = detail::CowPtr<Brick>;
  detail::CowPtr<std::vector<BrickPtr>> bricks_;
  std::size_t leaf_count_ = 0;
};

}  // namespace rtog
