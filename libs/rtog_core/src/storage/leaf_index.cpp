#include "storage/leaf_index.hpp"

#include <algorithm>

#include "parallel/parallel.hpp"
#include "storage/morton_order.hpp"

namespace rtog {

void LeafIndex::clear() {
  upper_.reset(UpperTree(upper_->tree.params()));
  brick_index_.reset(detail::FlatHashMap64{});
  bricks_.reset({});
  leaf_count_ = 0;
}

std::uint32_t LeafIndex::brickSlot(const Key& brick) {
  const std::uint64_t key = packKey(brick);
  const std::uint32_t found = brick_index_->find(key);
  if (found != detail::FlatHashMap64::kAbsent) return found;  // no clone of a shared hash to read it
  auto& bricks = bricks_.write();
  const auto slot = static_cast<std::uint32_t>(bricks.size());
  brick_index_.write().findOrInsert(key, slot);
  bricks.emplace_back(Brick{brick, {}});
  return slot;
}

const Brick* LeafIndex::findBrick(const Key& brick) const {
  const std::uint32_t slot = brick_index_->find(packKey(brick));
  return slot == detail::FlatHashMap64::kAbsent ? nullptr : (*bricks_)[slot].get();
}

void LeafIndex::reserveBricks(std::size_t more) {
  // Still growing geometrically.
  auto& bricks = bricks_.write();
  if (bricks.capacity() < bricks.size() + more) bricks.reserve(std::max(bricks.size() + more, 2 * bricks.capacity()));
}

Box LeafIndex::leafNodeBox(const Brick& b, std::size_t node) const {
  if (node * leafNodeSize() >= b.leaves.size()) return Box::empty();
  return localNodeBox(b.leaves, node).global(brickOrigin(b.brick));
}

LocalBox LeafIndex::localNodeBox(const std::vector<LeafEntry>& leaves, std::size_t node) const {
  // In brick-local bytes, one conversion at the end.
  const std::size_t first = node * leafNodeSize(), last = std::min(leaves.size(), first + leafNodeSize());
  LocalBox united = leaves[first];
  for (std::size_t i = first + 1; i < last; ++i)
    for (int a = 0; a < 3; ++a) {
      united.lo[a] = std::min(united.lo[a], leaves[i].lo[a]);
      united.hi[a] = std::max(united.hi[a], leaves[i].hi[a]);
    }
  return united;
}

const LeafEntry* LeafIndex::findLeaf(const Key& k) const {
  if (!keyInRange(k)) return nullptr;
  const std::uint32_t slot = brick_index_->find(packKey(brickOf(k)));
  if (slot == detail::FlatHashMap64::kAbsent) return nullptr;
  if (slot >= upper_->nodes.size()) return nullptr;  // a brick made but not yet in the tree
  const Brick* b = (*bricks_)[slot].get();
  const auto& nodes = upper_->nodes[slot];
  const Key l = localKey(localIndex(k));
  // Leaf-node boxes first, then the entries of the one node that can hold the cell.
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    if (!upper_->tree.box(nodes[n]).contains(k)) continue;
    const std::size_t first = n * leafNodeSize(), last = std::min(b->leaves.size(), first + leafNodeSize());
    for (std::size_t i = first; i < last; ++i)
      if (b->leaves[i].contains(l)) return &b->leaves[i];
  }
  return nullptr;
}

void LeafIndex::syncLeafNodes(std::uint32_t slot) {
  const Brick& br = brick(slot);
  UpperTree& up = upper_.write();
  if (up.nodes.size() < brickCount()) up.nodes.resize(brickCount());
  auto& handles = up.nodes[slot];
  const std::size_t nodes = leafNodeCount(br);
  for (std::size_t n = 0; n < nodes; ++n) {
    const Box box = leafNodeBox(br, n);
    if (n < handles.size()) {
      if (up.tree.box(handles[n]) != box) up.tree.updateBox(handles[n], box);
    } else {
      handles.push_back(up.tree.insert(box, LeafNodeRef{slot, static_cast<std::uint32_t>(n)}));
    }
  }
  while (handles.size() > nodes) {
    up.tree.remove(handles.back());
    handles.pop_back();
  }
}

void LeafIndex::refreshUpperTree(std::vector<std::uint32_t>& reshaped, int threads,
                                 const std::function<std::vector<const LocalBox*>()>& boxes_of) {
  // Leaf nodes whose boxes changed go into the upper tree one by one, unless they are many
  // compared with the tree (a first scan, a new area): then one bulk load is cheaper.
  std::size_t touched_nodes = 0;
  for (const std::uint32_t slot : reshaped) touched_nodes += leafNodeCount(brick(slot));
  if (touched_nodes * 2 > upper_->tree.size()) {
    rebuildUpperTree(threads, boxes_of ? boxes_of() : std::vector<const LocalBox*>{});
  } else {
    // In slot order: the tree must not depend on which thread applied which brick.
    std::sort(reshaped.begin(), reshaped.end());
    for (const std::uint32_t slot : reshaped) syncLeafNodes(slot);
  }
}

void LeafIndex::rebuildUpperTree(int threads, const std::vector<const LocalBox*>& boxes_of) {
  // Leaf nodes go to the bulk load in Morton order of their bricks, and a brick's nodes follow
  // its leaves, which are in Morton order of their first cells when packed: close to the order
  // of the nodes' own Morton codes without sorting the nodes (the load runs on one thread).
  const auto slots = static_cast<std::uint32_t>(brickCount());
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(slots);
  for (std::uint32_t slot = 0; slot < slots; ++slot) order[slot] = {mortonCode(brick(slot).brick), slot};
  // A first scan's bricks got their slots in this order already (update batches are in it).
  if (!std::is_sorted(order.begin(), order.end())) std::sort(order.begin(), order.end());
  // Handles are the nodes' positions in the load, so each brick knows its own before the load.
  std::vector<std::uint32_t> first_node(slots + 1, 0);
  for (std::uint32_t i = 0; i < slots; ++i)
    first_node[i + 1] = first_node[i] + static_cast<std::uint32_t>(leafNodeCount(brick(order[i].second)));
  std::vector<std::pair<Box, LeafNodeRef>> nodes(first_node[slots]);
  std::vector<std::uint32_t> rank(slots);  // of each slot in `order`
  for (std::uint32_t i = 0; i < slots; ++i) rank[order[i].second] = i;
  // A new tree (a shared one is left to its other owners, not cloned to be overwritten).
  UpperTree fresh(upper_->tree.params());
  fresh.nodes.resize(slots);
  // The leaf nodes' boxes read every leaf of the map: the threads take ranges of slots, not of
  // `order`, whose neighbours' handles (written here) would share cache lines.
  const auto collect = [&](std::size_t begin, std::size_t end) {
    for (auto slot = static_cast<std::uint32_t>(begin); slot < end; ++slot) {
      const std::uint32_t i = rank[slot];
      const Brick& br = brick(slot);
      auto& handles = fresh.nodes[slot];
      handles.resize(first_node[i + 1] - first_node[i]);
      const LocalBox* boxes = boxes_of.empty() ? nullptr : boxes_of[slot];
      const Key origin = brickOrigin(br.brick);
      for (std::uint32_t k = 0; k < handles.size(); ++k) {
        handles[k] = first_node[i] + k;
        nodes[handles[k]] = {boxes ? boxes[k].global(origin) : leafNodeBox(br, k), LeafNodeRef{slot, k}};
      }
    }
  };
  // Below some thousand bricks (or nodes) a thread costs more than it saves.
  const auto parts = [threads](std::size_t count) {
    return std::min<std::size_t>(static_cast<std::size_t>(std::max(threads, 1)), 1 + count / 1024);
  };
  parallel::forRanges(slots, parts(slots), collect);
  fresh.tree.bulkLoad(std::move(nodes), RTree<LeafNodeRef>::Packing::AsGiven,
                      [&](std::size_t count, const std::function<void(std::size_t, std::size_t)>& fn) {
                        parallel::forRanges(count, parts(count), fn);
                      });
  upper_.reset(std::move(fresh));
}

void LeafIndex::packLeaves(std::uint32_t slot, const std::vector<std::int32_t>& local) {
  Brick& br = mutableBrick(slot);
  std::vector<LeafEntry> live, packed;  // packed: exact capacity
  if (br.leaves.size() * 16 >= static_cast<std::size_t>(kBrickCells)) {
    // Dense brick: one pass over the cells in Morton order, taking each live leaf at its first cell.
    for (const std::uint16_t idx : mortonOrder()) {
      const std::int32_t i = local[idx];
      if (i < 0) continue;
      const LeafEntry& e = br.leaves[static_cast<std::size_t>(i)];
      if (localIndex(e.lo[0], e.lo[1], e.lo[2]) == idx) live.push_back(e);
    }
    packed.assign(live.begin(), live.end());
  } else {
    // Sparse brick: the few live leaves by the Morton rank of their first cell.
    for (const LeafEntry& e : br.leaves)
      if (e.lo[0] != kDead) live.push_back(e);
    assignByFirstCell(live, packed);
  }
  br.leaves.swap(packed);
}

std::size_t LeafIndex::memoryBytes() const {
  std::size_t bytes = upper_->tree.memoryBytes() + upper_->nodes.capacity() * sizeof(upper_->nodes[0]) +
                      brick_index_->memoryBytes() + bricks_->capacity() * sizeof(BrickPtr);
  for (const auto& h : upper_->nodes) bytes += h.heapBytes();
  for (const auto& b : *bricks_) bytes += sizeof(Brick) + b->leaves.capacity() * sizeof(LeafEntry);
  return bytes;
}

std::size_t LeafIndex::sharedBricks() const {
  std::size_t n = 0;
  // A shared array shares every brick.
  if (bricks_.shared()) return bricks_->size();
  for (const auto& b : *bricks_) n += b.shared();
  return n;
}

std::string LeafIndex::checkInvariants(const LogOddsModel& model, const std::function<bool(float)>& mergeable) const {
  // Leaf-node boxes may overlap (inner boxes of an R-tree); leaves may not, checked below.
  const RTree<LeafNodeRef>& upper = upper_->tree;
  std::string err = upper.checkInvariants(false);
  if (!err.empty()) return "R-tree: " + err;
  std::size_t leaves = 0, nodes = 0;
  std::vector<std::uint8_t> painted(kBrickCells);
  for (std::size_t slot = 0; slot < brickCount(); ++slot) {
    const Brick& b = brick(static_cast<std::uint32_t>(slot));
    if (brick_index_->find(packKey(b.brick)) != slot) return "brick index does not point at brick " + toString(b.brick);
    static const detail::SmallVector<Handle, 4> none{};
    const auto& handles = slot < upper_->nodes.size() ? upper_->nodes[slot] : none;
    if (handles.size() != leafNodeCount(b)) return "brick " + toString(b.brick) + " has the wrong number of leaf nodes";
    for (std::size_t n = 0; n < handles.size(); ++n) {
      const Handle h = handles[n];
      if (!upper.valid(h)) return "leaf node with a dead handle";
      const LeafNodeRef r = upper.payload(h);
      if (r.brick != slot || r.node != n) return "leaf node reference mismatch";
      if (upper.box(h) != leafNodeBox(b, n)) return "leaf node box is not the tight union of its entries";
    }
    nodes += handles.size();
    std::fill(painted.begin(), painted.end(), 0);
    for (const LeafEntry& e : b.leaves) {
      ++leaves;
      for (int a = 0; a < 3; ++a)
        if (e.lo[a] > e.hi[a] || e.hi[a] >= kBrickSize) return "malformed leaf in brick " + toString(b.brick);
      const Box gb = e.global(brickOrigin(b.brick));
      if (!(e.value >= model.clampMin() && e.value <= model.clampMax())) return "leaf value outside the clamping bounds";
      if (gb.volume() > 1 && !mergeable(e.value))
        return "merged leaf " + toString(gb) + " holds a value its policy does not merge";
      bool overlap = false;
      e.forEachCell([&](int i) { overlap |= painted[static_cast<std::size_t>(i)]++ != 0; });
      if (overlap) return "leaves overlap at " + toString(gb);
    }
  }
  if (leaves != leaf_count_) return "leaf count mismatch";
  if (brick_index_->size() != brickCount()) return "brick index and bricks disagree on the number of bricks";
  if (nodes != upper.size()) return "upper tree and bricks disagree on the number of leaf nodes";
  return {};
}

}  // namespace rtog
