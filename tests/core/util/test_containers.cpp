#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "util/radix_sort.hpp"
#include "util/small_vector.hpp"

using namespace rtog;

TEST(RadixSort, OrdersPairsAsStdSortDoes) {
  std::mt19937_64 rng(11);
  for (const std::size_t n : {0u, 1u, 2u, 7u, 1000u, 20000u})
    for (const std::uint64_t mask :
         {~std::uint64_t{0}, std::uint64_t{0xFFFF}, std::uint64_t{0xF0F000}, std::uint64_t{7}}) {
      // Keys in index order, as callers build them: duplicates must stay in index order.
      std::vector<std::pair<std::uint64_t, std::uint32_t>> items(n);
      const std::uint64_t high = rng() & ~mask;  // bytes all keys share
      for (std::size_t i = 0; i < n; ++i) items[i] = {high | (rng() & mask), static_cast<std::uint32_t>(i)};
      auto expected = items;
      std::sort(expected.begin(), expected.end());
      detail::radixSortByKey(items);
      ASSERT_EQ(items, expected) << n << " keys, mask " << mask;
    }
}

TEST(SmallVector, BehavesAsStdVectorInlineAndOnTheHeap) {
  // Random pushes, pops, resizes, copies and moves, checked against std::vector after each.
  std::mt19937 rng(5);
  using Small = detail::SmallVector<std::uint32_t, 4>;
  std::vector<Small> smalls(3);
  std::vector<std::vector<std::uint32_t>> plain(3);
  for (int step = 0; step < 20000; ++step) {
    const std::size_t i = rng() % 3, j = rng() % 3;
    switch (rng() % 7) {
      case 0:
      case 1: {
        const std::uint32_t v = rng();
        smalls[i].push_back(v);
        plain[i].push_back(v);
        break;
      }
      case 2:
        if (!plain[i].empty()) smalls[i].pop_back(), plain[i].pop_back();
        break;
      case 3: {
        const std::size_t n = rng() % 12;
        smalls[i].resize(n);
        plain[i].resize(n);
        break;
      }
      case 4:
        smalls[i] = smalls[j];
        plain[i] = plain[j];
        break;
      case 5:
        if (i != j) {
          smalls[i] = std::move(smalls[j]);
          plain[i] = std::move(plain[j]);
          plain[j].clear();  // a moved-from SmallVector is empty
        }
        break;
      default: {
        Small copy(smalls[i]);
        Small moved(std::move(copy));
        ASSERT_TRUE(copy.empty());
        ASSERT_EQ(moved.size(), plain[i].size());
      }
    }
    for (std::size_t k = 0; k < 3; ++k) {
      ASSERT_EQ(smalls[k].size(), plain[k].size()) << "step " << step;
      for (std::size_t e = 0; e < plain[k].size(); ++e) ASSERT_EQ(smalls[k][e], plain[k][e]) << "step " << step;
      // Inline up to 4 values: no heap.
      if (plain[k].size() <= 4 && smalls[k].heapBytes() == 0) continue;
      ASSERT_GE(smalls[k].heapBytes(), plain[k].size() * sizeof(std::uint32_t));
    }
  }
}

