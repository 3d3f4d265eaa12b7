// The core's FlatHashMap64 against tsl::robin_map (which the MRPT adapter uses) on the core's
// own use: packed 64-bit cell/brick keys of a spatially coherent scan, each met a few times,
// mapped to a small slot index (insert-or-accumulate), then looked up again (find).
// Not a test: `rtog-core-micro --benchmark_filter=HashMap` on a quiet machine.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include <tsl/robin_map.h>

#include "rtog/core/key.hpp"
#include "util/flat_hash_map.hpp"

namespace {

/// The core's mix of a packed key (FlatHashMap64::bucket). tsl::robin_map's default,
/// std::hash<std::uint64_t>, is the identity on libstdc++: with a power-of-two table only the
/// key's low bits (x) choose the bucket, and a block of cells piles into few of them.
struct MixedHash {
  std::size_t operator()(std::uint64_t key) const {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdull;
    key ^= key >> 33;
    return static_cast<std::size_t>(key);
  }
};
using RobinIdentity = tsl::robin_map<std::uint64_t, std::uint32_t>;  // as the adapter declares it
using RobinMixed = tsl::robin_map<std::uint64_t, std::uint32_t, MixedHash>;

/// n distinct keys packed by packKey from a dense block of cells, each
/// appearing 4 times, shuffled with a fixed seed.
std::vector<std::uint64_t> scanKeys(std::size_t n) {
  std::vector<std::uint64_t> keys;
  keys.reserve(4 * n);
  const std::size_t side = 128;  // x, y in [-64, 64), z grows with n
  for (std::size_t i = 0; i < n; ++i) {
    const rtog::Key key{static_cast<std::int32_t>(i % side) - 64, static_cast<std::int32_t>((i / side) % side) - 64,
                        static_cast<std::int32_t>(i / (side * side))};
    const std::uint64_t k = rtog::packKey(key);
    for (int r = 0; r < 4; ++r) keys.push_back(k);
  }
  std::mt19937_64 rng(38);
  std::shuffle(keys.begin(), keys.end(), rng);
  return keys;
}

void BM_HashMap_Flat_Accumulate(benchmark::State& st) {
  const auto keys = scanKeys(static_cast<std::size_t>(st.range(0)));
  for (auto _ : st) {
    rtog::detail::FlatHashMap64 map;
    std::vector<std::uint32_t> counts;
    for (std::uint64_t k : keys) {
      const std::uint32_t slot = map.findOrInsert(k, static_cast<std::uint32_t>(counts.size()));
      if (slot == counts.size()) counts.push_back(0);
      ++counts[slot];
    }
    benchmark::DoNotOptimize(counts.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(keys.size()));
}

template <class Map>
void BM_HashMap_Robin_Accumulate(benchmark::State& st) {
  const auto keys = scanKeys(static_cast<std::size_t>(st.range(0)));
  for (auto _ : st) {
    Map map;
    for (std::uint64_t k : keys) ++map[k];
    benchmark::DoNotOptimize(map.size());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(keys.size()));
}

void BM_HashMap_Flat_Find(benchmark::State& st) {
  const auto keys = scanKeys(static_cast<std::size_t>(st.range(0)));
  rtog::detail::FlatHashMap64 map;
  std::uint32_t next = 0;
  for (std::uint64_t k : keys)
    if (map.findOrInsert(k, next) == next) ++next;
  for (auto _ : st) {
    std::uint64_t sum = 0;
    for (std::uint64_t k : keys) sum += map.find(k);
    benchmark::DoNotOptimize(sum);
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(keys.size()));
}

template <class Map>
void BM_HashMap_Robin_Find(benchmark::State& st) {
  const auto keys = scanKeys(static_cast<std::size_t>(st.range(0)));
  Map map;
  std::uint32_t next = 0;
  for (std::uint64_t k : keys)
    if (map.try_emplace(k, next).second) ++next;
  for (auto _ : st) {
    std::uint64_t sum = 0;
    for (std::uint64_t k : keys) sum += map.find(k)->second;
    benchmark::DoNotOptimize(sum);
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(keys.size()));
}

}  // namespace

BENCHMARK(BM_HashMap_Flat_Accumulate)->RangeMultiplier(10)->Range(10000, 1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_HashMap_Robin_Accumulate, RobinMixed)->RangeMultiplier(10)->Range(10000, 1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_HashMap_Robin_Accumulate, RobinIdentity)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HashMap_Flat_Find)->RangeMultiplier(10)->Range(10000, 1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_HashMap_Robin_Find, RobinMixed)->RangeMultiplier(10)->Range(10000, 1000000)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_HashMap_Robin_Find, RobinIdentity)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
