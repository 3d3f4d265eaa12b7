// Direct tests of the core's hand-written containers and the parallel chunk claims, each
// against a standard-library oracle (random operations, fixed seeds).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <random>
#include <unordered_map>
#include <vector>

#include "parallel/parallel.hpp"
#include "util/chunked_vector.hpp"
#include "util/flat_hash_map.hpp"

using namespace rtog;

TEST(FlatHashMap64, MatchesUnorderedMapOnRandomKeysThroughGrowth) {
  // Random 64-bit keys (all-ones is the empty marker and never a packed key) drawn from a small
  // pool so that keys repeat; the table grows from empty through several doublings.
  std::mt19937_64 rng(38);
  std::vector<std::uint64_t> pool(20000);
  for (auto& k : pool) {
    do k = rng();
    while (k == ~std::uint64_t{0});
  }
  detail::FlatHashMap64 map;
  std::unordered_map<std::uint64_t, std::uint32_t> oracle;
  EXPECT_EQ(map.find(pool[0]), detail::FlatHashMap64::kAbsent);  // empty table
  for (int step = 0; step < 60000; ++step) {
    const std::uint64_t k = pool[rng() % pool.size()];
    const auto v = static_cast<std::uint32_t>(rng() % 1000000);
    const auto it = oracle.emplace(k, v).first;
    ASSERT_EQ(map.findOrInsert(k, v), it->second) << "step " << step;
    ASSERT_EQ(map.size(), oracle.size());
  }
  EXPECT_GT(map.memoryBytes(), oracle.size() * 12);  // grew: at most 3/4 full
  for (const auto& [k, v] : oracle) ASSERT_EQ(map.find(k), v);
  std::mt19937_64 other(7);  // keys never inserted
  for (int i = 0; i < 10000; ++i) {
    const std::uint64_t k = other();
    if (!oracle.count(k)) {
      ASSERT_EQ(map.find(k), detail::FlatHashMap64::kAbsent);
    }
  }
  map.clear();
  EXPECT_TRUE(map.empty());
  for (const auto& [k, v] : oracle) ASSERT_EQ(map.find(k), detail::FlatHashMap64::kAbsent);
}

TEST(FlatHashMap64, KeysCollidingInTheLowBitsStayApart) {
  // Keys that differ only above bit 40 (packed keys differing in z only): probing must keep them.
  detail::FlatHashMap64 map;
  for (std::uint32_t i = 0; i < 5000; ++i) map.findOrInsert(std::uint64_t{i} << 42, i);
  ASSERT_EQ(map.size(), 5000u);
  for (std::uint32_t i = 0; i < 5000; ++i) ASSERT_EQ(map.find(std::uint64_t{i} << 42), i);
  EXPECT_EQ(map.find(std::uint64_t{5000} << 42), detail::FlatHashMap64::kAbsent);
}

TEST(ChunkedVector, BehavesAsStdVectorAcrossChunksAndClears) {
  std::mt19937 rng(38);
  detail::ChunkedVector<std::uint64_t, 16> chunked;
  std::vector<std::uint64_t> plain;
  std::vector<const std::uint64_t*> addresses;  // growth never moves an element
  for (int step = 0; step < 20000; ++step) {
    const unsigned op = rng() % 100;
    if (op < 85) {
      std::uint64_t& e = chunked.emplaceBack();
      ASSERT_EQ(e, 0u);  // value-initialized even when a chunk is reused
      e = rng();
      plain.push_back(e);
      addresses.push_back(&e);
    } else if (op < 98 && !plain.empty()) {
      const std::size_t i = rng() % plain.size();
      chunked[i] += 1;
      plain[i] += 1;
    } else if (op == 98) {
      const std::size_t cap = chunked.capacity();
      chunked.clear();
      plain.clear();
      addresses.clear();
      ASSERT_EQ(chunked.capacity(), cap);  // keeps its chunks
    } else {
      chunked.release();
      plain.clear();
      addresses.clear();
      ASSERT_EQ(chunked.capacity(), 0u);
    }
    ASSERT_EQ(chunked.size(), plain.size());
    ASSERT_GE(chunked.capacity(), chunked.size());
    ASSERT_EQ(chunked.capacity() % 16, 0u);
  }
  const auto& view = chunked;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    ASSERT_EQ(view[i], plain[i]);
    ASSERT_EQ(&view[i], addresses[i]);
  }
}

TEST(ChunkClaims, EveryChunkIsClaimedExactlyOnceForRandomCountsAndThreads) {
  std::mt19937 rng(38);
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t chunks = trial < 3 ? static_cast<std::size_t>(trial) : rng() % 5000;
    const std::size_t threads = 1 + rng() % 8;
    parallel::ChunkClaims claims(chunks, threads);
    std::vector<std::atomic<int>> taken(chunks);
    std::atomic<std::size_t> out_of_range{0};
    parallel::run(threads, [&](std::size_t t) {
      for (std::size_t c; (c = claims.next(t)) != parallel::ChunkClaims::kNone;) {
        if (c >= chunks)
          ++out_of_range;
        else
          ++taken[c];
      }
    });
    ASSERT_EQ(out_of_range.load(), 0u) << chunks << " chunks, " << threads << " threads";
    for (std::size_t c = 0; c < chunks; ++c)
      ASSERT_EQ(taken[c].load(), 1) << "chunk " << c << " of " << chunks << ", " << threads << " threads";
    // Once all are taken, every thread is told so.
    for (std::size_t t = 0; t < threads; ++t) ASSERT_EQ(claims.next(t), parallel::ChunkClaims::kNone);
  }
}

// The integrators' tracing skeleton: every item traced once in chunks of the given size (the last
// one shorter), each thread begun and finished once, counts per thread summing to the items; a
// trace returning false stops every thread at its next chunk and skips every finish.
TEST(TraceChunks, TracesEveryItemOnceAndStopsEveryThreadOnFalse) {
  std::mt19937 rng(39);
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t count = trial == 0 ? 0 : rng() % 20000, chunk = 1 + rng() % 700, threads = 1 + rng() % 6;
    std::vector<std::atomic<int>> traced(count);
    std::vector<std::atomic<int>> begun(threads), finished(threads);
    std::vector<std::size_t> counts(threads);
    std::atomic<bool> bad_chunk{false};
    const bool all = parallel::traceChunks(
        count, chunk, counts, [&](std::size_t t) { ++begun[t]; },
        [&](std::size_t, std::size_t first, std::size_t n, std::size_t& own) {
          if (first % chunk != 0 || n == 0 || n > chunk || (n < chunk && first + n != count)) bad_chunk = true;
          for (std::size_t i = first; i < first + n; ++i) ++traced[i];
          own += n;
          return true;
        },
        [&](std::size_t t) { ++finished[t]; });
    ASSERT_TRUE(all);
    ASSERT_FALSE(bad_chunk.load()) << count << " items, chunk " << chunk;
    std::size_t sum = 0;
    for (std::size_t t = 0; t < threads; ++t) {
      ASSERT_EQ(begun[t].load(), 1);
      ASSERT_EQ(finished[t].load(), 1);
      sum += counts[t];
    }
    ASSERT_EQ(sum, count);
    for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(traced[i].load(), 1) << "item " << i;

    // A chunk that fails: no finish runs. When every chunk fails, each thread traces at most one
    // (it stops itself), whatever the timing.
    if (count == 0) continue;
    const std::size_t failing = rng() % ((count + chunk - 1) / chunk);
    for (const bool every : {false, true}) {
      std::vector<std::atomic<int>> finished2(threads), per_thread(threads);
      const bool all2 = parallel::traceChunks(
          count, chunk, counts, [](std::size_t) {},
          [&](std::size_t t, std::size_t first, std::size_t, std::size_t&) {
            ++per_thread[t];
            return !(every || first / chunk == failing);
          },
          [&](std::size_t t) { ++finished2[t]; });
      ASSERT_FALSE(all2);
      for (std::size_t t = 0; t < threads; ++t) {
        ASSERT_EQ(finished2[t].load(), 0);
        if (every) {
          ASSERT_LE(per_thread[t].load(), 1);
        }
      }
    }
  }
}
