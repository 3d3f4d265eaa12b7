// Sorting (key, index) pairs by key: a least-significant-byte radix sort, stable, that skips the
// bytes in which all keys agree (Morton codes of nearby boxes share their high bytes). It puts
// pairs built in index order in the order std::sort gives them, ties by index.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace rtog {
namespace detail {

inline void radixSortByKey(std::vector<std::pair<std::uint64_t, std::uint32_t>>& items) {
  if (items.size() < 2) return;
  std::uint64_t all_or = 0, all_and = ~std::uint64_t{0};
  for (const auto& it : items) all_or |= it.first, all_and &= it.first;
  const std::uint64_t varying = all_or ^ all_and;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> other(items.size());
  for (int shift = 0; shift < 64; shift += 8) {
    if (((varying >> shift) & 0xFFu) == 0) continue;
    std::array<std::size_t, 256> start{};
    for (const auto& it : items) ++start[(it.first >> shift) & 0xFFu];
    std::size_t sum = 0;
    for (std::size_t& s : start) {
      const std::size_t count = s;
      s = sum;
      sum += count;
    }
    for (const auto& it : items) other[start[(it.first >> shift) & 0xFFu]++] = it;
    items.swap(other);
  }
}

}  // namespace detail
}  // namespace rtog
