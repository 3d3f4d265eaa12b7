// libFuzzer target: the core `.rtog` format (OccupancyMap::read) from arbitrary bytes.
//
// A random mutation almost never keeps the FNV-1a checksum right, so most inputs would stop at
// "checksum mismatch" and the leaf checks behind it would go unexplored. Each input is therefore
// read twice: as given, and with the checksum recomputed where the header's leaf count puts it.
// A map that loads must be sound and must survive a write/read round trip unchanged.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include "rtog/core/occupancy_map.hpp"

namespace {

constexpr std::size_t kMagic = 8;
// version u32, 7 x f64, merge u8, 2 x u32 R-tree parameters, then the u64 leaf count.
constexpr std::size_t kCountAt = kMagic + 4 + 7 * 8 + 1 + 2 * 4;
constexpr std::size_t kLeafBytes = 6 * 4 + 4;

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "rtog_fuzz_core_map: %s: %s\n", what, detail.c_str());
  std::abort();
}

void check(const std::string& bytes) {
  rtog::OccupancyMap map;
  try {
    std::istringstream is(bytes, std::ios::binary);
    map = rtog::OccupancyMap::read(is);
  } catch (const std::runtime_error&) {
    return;  // rejected with a reason: what the format promises for bad input
  }
  if (const std::string why = map.checkInvariants(); !why.empty()) fail("loaded map is unsound", why);
  // Every query must work on whatever loaded.
  const rtog::MapStatistics s = map.statistics();
  if (s.leaves != map.leafCount()) fail("statistics", "leaf count disagrees");
  (void)map.classCover();
  const Eigen::Vector3d o(0.01, 0.02, 0.03);
  (void)map.castRay(o, Eigen::Vector3d(1, 0.5, 0.25), 5.0);
  (void)map.nearestOccupied(o, 2.0);
  if (!s.bounds.isEmpty()) (void)map.summarize(s.bounds);
  std::ostringstream out(std::ios::binary);
  map.write(out);
  std::istringstream again(out.str(), std::ios::binary);
  const rtog::OccupancyMap back = rtog::OccupancyMap::read(again);
  std::ostringstream out2(std::ios::binary);
  back.write(out2);
  if (out.str() != out2.str()) fail("round trip", "a loaded map does not write back the same bytes");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  check(bytes);
  if (size < kCountAt + 8) return 0;
  std::uint64_t count;
  std::memcpy(&count, data + kCountAt, sizeof(count));
  if (count > (size - kCountAt - 8) / kLeafBytes) return 0;
  const std::size_t sum_at = kCountAt + 8 + static_cast<std::size_t>(count) * kLeafBytes;
  if (sum_at + 8 > size) return 0;
  std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a of the bytes after the magic (doc/format.md)
  for (std::size_t i = kMagic; i < sum_at; ++i) h = (h ^ data[i]) * 0x100000001b3ull;
  std::memcpy(&bytes[sum_at], &h, sizeof(h));
  check(bytes);
  return 0;
}
