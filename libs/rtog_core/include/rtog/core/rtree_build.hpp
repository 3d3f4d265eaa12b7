// Insertion, node splits, condensing and bulk loading of rtog::RTree, out of the class (included by rtree.hpp only).
#pragma once

#include "rtog/core/rtree.hpp"

namespace rtog {

template <class Payload>
auto RTree<Payload>::bulkLoad(std::vector<std::pair<Box, Payload>> items, Packing packing,
              const RangeRunner& for_ranges) -> void {
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
    packLeafLevel(items, for_ranges, level);
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

template <class Payload>
auto RTree<Payload>::chooseNode(const Box& b, std::uint16_t level) const -> std::uint32_t {
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

template <class Payload>
auto RTree<Payload>::insertEntry(const Box& b, std::uint32_t id, std::uint16_t level) -> void {
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

template <class Payload>
auto RTree<Payload>::split(std::uint32_t n) -> std::uint32_t {
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

template <class Payload>
auto RTree<Payload>::condense(std::uint32_t n) -> void {
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

template <class Payload>
auto RTree<Payload>::reinsertSubtreeEntries(std::uint32_t node) -> void {
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

template <class Payload>
auto RTree<Payload>::mortonSort(std::vector<Entry>& es) -> void {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order(es.size());
  for (std::size_t i = 0; i < es.size(); ++i) {
    const Box& b = es[i].box;
    // Centre on the lattice, rounded down.
    const auto mid = [&](int a) { return static_cast<std::int32_t>((std::int64_t{b.min[a]} + b.max[a]) >> 1); };
    order[i] = {mortonCode(Key{mid(0), mid(1), mid(2)}), static_cast<std::uint32_t>(i)};
  }
  std::sort(order.begin(), order.end());
  std::vector<Entry> sorted;
  sorted.reserve(es.size());
  for (const auto& o : order) sorted.push_back(es[o.second]);
  es.swap(sorted);
}

template <class Payload>
auto RTree<Payload>::packLeafLevel(std::vector<std::pair<Box, Payload>>& items, const RangeRunner& for_ranges,
                   std::vector<Entry>& level) -> void {
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
  if (for_ranges) {
    for_ranges(ends.size(), fill);
  } else {
    fill(0, ends.size());
  }
}

template <class Payload>
auto RTree<Payload>::runEnds(std::size_t n) const -> std::vector<std::size_t> {
  const std::size_t M = params_.max_entries, m = params_.min_entries;
  std::vector<std::size_t> ends;
  for (std::size_t k = M; k < n + M; k += M) ends.push_back(std::min(n, k));
  if (ends.size() > 1) {
    const std::size_t last = n - ends[ends.size() - 2];
    if (last < m) ends[ends.size() - 2] -= m - last;
  }
  return ends;
}

template <class Payload>
auto RTree<Payload>::strPack(std::vector<Entry> es) const -> std::vector<std::vector<Entry>> {
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

template <class Payload>
auto RTree<Payload>::fixFill(std::vector<std::vector<Entry>>& out) const -> void {
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

}  // namespace rtog
