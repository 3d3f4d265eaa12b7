// A cheap 64-bit fingerprint of the bytes an observation's decoded points depend on, so that a
// cache of decoded points is keyed by content and not by the object's address or timestamp
// (both are reused: rawlogs whose scans share a timestamp, observations changed in place).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

namespace rtog::detail {

class Fingerprint {
 public:
  /// Mixes `n` bytes: 32 bytes per step in four independent lanes (a depth image is ~600 KB and
  /// a particle filter fingerprints it once per particle).
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    value(n);
    std::uint64_t l[4] = {lane_[0], lane_[1], lane_[2], lane_[3]};
    for (; n >= 32; n -= 32, p += 32)
      for (int i = 0; i < 4; ++i) l[i] = mix(l[i], load(p + 8 * i));
    for (int i = 0; i < 4; ++i) lane_[i] = l[i];
    for (; n >= 8; n -= 8, p += 8) lane_[0] = mix(lane_[0], load(p));
    if (n) {
      std::uint64_t w = 0;
      std::memcpy(&w, p, n);
      lane_[1] = mix(lane_[1], w ^ (std::uint64_t(n) << 56));
    }
  }
  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    std::uint64_t w[(sizeof(T) + 7) / 8] = {};
    std::memcpy(w, &v, sizeof(T));
    for (std::uint64_t x : w) lane_[2] = mix(lane_[2], x);
  }
  void text(const std::string& s) { bytes(s.data(), s.size()); }
  template <class T>
  void vector(const std::vector<T>& v) {
    bytes(v.data(), v.size() * sizeof(T));
  }
  std::uint64_t digest() const {
    std::uint64_t h = 0x2545F4914F6CDD1Dull;
    for (std::uint64_t l : lane_) h = mix(h, l);
    return h ^ (h >> 31);
  }

 private:
  static std::uint64_t load(const unsigned char* p) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    return w;
  }
  static std::uint64_t mix(std::uint64_t h, std::uint64_t w) {
    h = (h ^ w) * 0x9E3779B97F4A7C15ull;
    return h ^ (h >> 29);
  }
  std::uint64_t lane_[4] = {0x243F6A8885A308D3ull, 0x13198A2E03707344ull, 0xA4093822299F31D0ull,
                            0x082EFA98EC4E6C89ull};
};

}  // namespace rtog::detail
