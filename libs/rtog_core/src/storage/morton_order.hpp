// Morton (Z-order) order of a brick's cells: leaves kept in the Morton order of their first
// cell keep the leaf nodes cut from a brick's array compact.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "storage/brick.hpp"

namespace rtog {

/// Local cell indices in Morton order.
const std::array<std::uint16_t, kBrickCells>& mortonOrder();
/// Inverse of mortonOrder(): the Morton rank of each local cell index.
const std::array<std::uint16_t, kBrickCells>& mortonRank();

/// Replaces `to` by the boxes of `from` in Morton order of their first cells. Disjoint boxes
/// have distinct first cells, so a bit per rank sorts them in O(n + 64 words). Scratch on the
/// stack: thread_local would cost a TLS call per brick in a shared library.
template <class From, class Out>
void assignByFirstCell(const From& from, Out& to) {
  const auto& rank = mortonRank();
  BrickMask present{};
  std::array<std::uint32_t, kBrickCells> index_at;  // read only where `present` is set
  for (std::size_t i = 0; i < from.size(); ++i) {
    const auto& e = from[i];
    const std::uint16_t r = rank[static_cast<std::size_t>(localIndex(e.lo[0], e.lo[1], e.lo[2]))];
    present[r >> 6] |= std::uint64_t{1} << (r & 63);
    index_at[r] = static_cast<std::uint32_t>(i);
  }
  to.clear();
  to.reserve(from.size());
  for (std::size_t w = 0; w < kBrickWords; ++w)
    for (std::uint64_t bits = present[w]; bits; bits &= bits - 1)
      to.push_back(from[index_at[w * 64 + static_cast<std::size_t>(__builtin_ctzll(bits))]]);
}

}  // namespace rtog
