#include "archive_read.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <mrpt/core/reverse_bytes.h>

namespace rtog::archive {
namespace {
constexpr std::size_t kChunk = std::size_t{1} << 20;

std::runtime_error corrupt(const char* who, const char* what, const std::string& why) {
  return std::runtime_error(std::string(who) + ": corrupt stream (" + what + ": " + why + ")");
}
}  // namespace

void readBytes(mrpt::serialization::CArchive& in, std::uint64_t n, std::string& out, const char* who,
               const char* what) {
  out.clear();
  while (out.size() < n) {
    const std::size_t at = out.size();
    const std::size_t chunk = static_cast<std::size_t>(std::min<std::uint64_t>(kChunk, n - at));
    out.resize(at + chunk);
    std::size_t got = 0;
    try {
      got = in.ReadBuffer(&out[at], chunk);
    } catch (const std::exception&) {
      got = 0;  // CArchive throws when nothing at all is left
    }
    if (got != chunk)
      throw std::runtime_error(std::string(who) + ": truncated stream (" + what + ": " + std::to_string(n) +
                               " bytes announced, the stream ends after " + std::to_string(at + got) + ")");
  }
}

std::string readString(mrpt::serialization::CArchive& in, std::size_t max_len, const char* who, const char* what) {
  const auto n = in.ReadAs<uint32_t>();
  if (n > max_len)
    throw corrupt(who, what, "a " + std::to_string(n) + "-byte string, at most " + std::to_string(max_len) + " allowed");
  std::string s;
  readBytes(in, n, s, who, what);
  return s;
}

std::vector<float> readFloats(mrpt::serialization::CArchive& in, std::size_t max_count, const char* who,
                              const char* what) {
  const auto n = in.ReadAs<uint32_t>();
  if (n > max_count)
    throw corrupt(who, what, std::to_string(n) + " values, at most " + std::to_string(max_count) + " allowed");
  std::string bytes;
  readBytes(in, std::uint64_t{n} * sizeof(float), bytes, who, what);
  std::vector<float> v(n);
  if (n) std::memcpy(v.data(), bytes.data(), bytes.size());
#if MRPT_IS_BIG_ENDIAN
  for (float& f : v) mrpt::reverseBytesInPlace(f);  // CArchive is little-endian
#endif
  return v;
}

mrpt::serialization::CArchive& operator>>(mrpt::serialization::CArchive& in, Flag f) {
  const auto byte = in.ReadAs<std::uint8_t>();
  if (byte > 1)
    throw std::runtime_error(std::string("rtog: corrupt stream (") + f.what + ": a bool stored as " +
                             std::to_string(int(byte)) + ")");
  f.value = byte == 1;
  return in;
}

}  // namespace rtog::archive
