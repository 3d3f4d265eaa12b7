#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "util/small_vector.hpp"

using namespace rtog;

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

