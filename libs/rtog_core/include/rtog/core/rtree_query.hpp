// Queries and the invariant checker of rtog::RTree, out of the class (included by rtree.hpp only).
#pragma once

#include "rtog/core/rtree.hpp"

namespace rtog {

template <class Payload>
template <class Visitor>
auto RTree<Payload>::queryBox(const Box& query, Visitor&& visitor) const -> void {
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

template <class Payload>
auto RTree<Payload>::checkInvariants(bool require_disjoint_entries) const -> std::string {
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

template <class Payload>
template <class KeyOf, class Pred>
auto RTree<Payload>::bestFirst(KeyOf&& key_of, Pred& pred, double limit) const -> Hit {
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

template <class Payload>
template <class Visitor>
auto RTree<Payload>::queryRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_max, Visitor&& visitor) const -> void {
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

}  // namespace rtog
