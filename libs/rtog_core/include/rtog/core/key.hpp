// Integer lattice: keys, boxes and the world <-> key conversion.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

namespace rtog {

/// Integer cell coordinates on the lattice. Cell k covers [k*res, (k+1)*res) per axis.
struct Key {
  std::int32_t x = 0, y = 0, z = 0;

  constexpr std::int32_t operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
  constexpr std::int32_t& operator[](int axis) { return axis == 0 ? x : (axis == 1 ? y : z); }
  friend constexpr bool operator==(const Key& a, const Key& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
  friend constexpr bool operator!=(const Key& a, const Key& b) { return !(a == b); }
  friend constexpr bool operator<(const Key& a, const Key& b) {
    return a.z != b.z ? a.z < b.z : (a.y != b.y ? a.y < b.y : a.x < b.x);
  }
};

/// Keys are limited to 21 bits per axis so that a key packs into 64 bits and sums of
/// extents never overflow; at 5 cm that is +-52 km around the origin.
/// Leaves lie inside aligned cubes ("bricks") of 2^kBrickBits cells a side, in the map and in
/// its file format (doc/format.md).
constexpr int kBrickBits = 4;

constexpr int kKeyBits = 21;
constexpr std::int32_t kKeyMin = -(1 << (kKeyBits - 1));
constexpr std::int32_t kKeyMax = (1 << (kKeyBits - 1)) - 1;

constexpr bool keyInRange(const Key& k) {
  return k.x >= kKeyMin && k.x <= kKeyMax && k.y >= kKeyMin && k.y <= kKeyMax && k.z >= kKeyMin &&
         k.z <= kKeyMax;
}

/// Packs an in-range key into 63 bits (for hashing and ordering).
constexpr std::uint64_t packKey(const Key& k) {
  constexpr std::uint64_t mask = (std::uint64_t{1} << kKeyBits) - 1;
  return (static_cast<std::uint64_t>(k.x - kKeyMin) & mask) |
         ((static_cast<std::uint64_t>(k.y - kKeyMin) & mask) << kKeyBits) |
         ((static_cast<std::uint64_t>(k.z - kKeyMin) & mask) << (2 * kKeyBits));
}
constexpr Key unpackKey(std::uint64_t p) {
  constexpr std::uint64_t mask = (std::uint64_t{1} << kKeyBits) - 1;
  return Key{static_cast<std::int32_t>(p & mask) + kKeyMin,
             static_cast<std::int32_t>((p >> kKeyBits) & mask) + kKeyMin,
             static_cast<std::int32_t>((p >> (2 * kKeyBits)) & mask) + kKeyMin};
}

/// Morton (Z-order) code of an in-range key: the bits of its unsigned coordinates interleaved,
/// x lowest. Keys close in space mostly get codes close in order.
constexpr std::uint64_t mortonCode(const Key& k) {
  const auto spread = [](std::uint64_t v) {  // 21 bits -> every third bit of 63
    v &= 0x1FFFFF;
    v = (v | v << 32) & 0x1F00000000FFFFull;
    v = (v | v << 16) & 0x1F0000FF0000FFull;
    v = (v | v << 8) & 0x100F00F00F00F00Full;
    v = (v | v << 4) & 0x10C30C30C30C30C3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
  };
  return spread(static_cast<std::uint64_t>(k.x - kKeyMin)) | spread(static_cast<std::uint64_t>(k.y - kKeyMin)) << 1 |
         spread(static_cast<std::uint64_t>(k.z - kKeyMin)) << 2;
}

struct KeyHash {
  std::size_t operator()(const Key& k) const noexcept {
    std::uint64_t h = packKey(k) * 0x9E3779B97F4A7C15ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
};

/// Inclusive integer box [min, max] on the lattice; the shape of every leaf entry.
struct Box {
  Key min, max;

  static constexpr Box cell(const Key& k) { return Box{k, k}; }
  static constexpr Box empty() {
    return Box{Key{kKeyMax + 1, kKeyMax + 1, kKeyMax + 1}, Key{kKeyMin - 1, kKeyMin - 1, kKeyMin - 1}};
  }

  constexpr bool isEmpty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
  constexpr std::int64_t extent(int axis) const { return std::int64_t{max[axis]} - min[axis] + 1; }
  constexpr std::int64_t volume() const { return isEmpty() ? 0 : extent(0) * extent(1) * extent(2); }
  constexpr bool contains(const Key& k) const {
    return k.x >= min.x && k.x <= max.x && k.y >= min.y && k.y <= max.y && k.z >= min.z && k.z <= max.z;
  }
  constexpr bool contains(const Box& b) const { return contains(b.min) && contains(b.max); }
  constexpr bool intersects(const Box& b) const {
    return min.x <= b.max.x && b.min.x <= max.x && min.y <= b.max.y && b.min.y <= max.y && min.z <= b.max.z &&
           b.min.z <= max.z;
  }
  constexpr Box intersection(const Box& b) const {
    return Box{Key{std::max(min.x, b.min.x), std::max(min.y, b.min.y), std::max(min.z, b.min.z)},
               Key{std::min(max.x, b.max.x), std::min(max.y, b.max.y), std::min(max.z, b.max.z)}};
  }
  constexpr Box united(const Box& b) const {
    return Box{Key{std::min(min.x, b.min.x), std::min(min.y, b.min.y), std::min(min.z, b.min.z)},
               Key{std::max(max.x, b.max.x), std::max(max.y, b.max.y), std::max(max.z, b.max.z)}};
  }
  friend constexpr bool operator==(const Box& a, const Box& b) { return a.min == b.min && a.max == b.max; }
  friend constexpr bool operator!=(const Box& a, const Box& b) { return !(a == b); }
};

std::string toString(const Key& k);
std::string toString(const Box& b);

/// Calls fn(key) for every cell of a non-empty box, x fastest.
template <class Fn>
void forEachCell(const Box& b, Fn&& fn) {
  for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
    for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
      for (std::int32_t x = b.min.x; x <= b.max.x; ++x) fn(Key{x, y, z});
}

/// floor() for values known to fit in int32: without SSE4.1 std::floor is a library call,
/// and this runs once per axis per beam.
inline std::int32_t floorToInt(double v) {
  const auto i = static_cast<std::int32_t>(v);  // truncates towards zero
  return i - static_cast<std::int32_t>(v < static_cast<double>(i));
}

/// The lattice geometry: resolution with cell boundaries at integer multiples of it (the
/// same alignment as OctoMap, so that both maps can be compared cell by cell).
class Lattice {
 public:
  explicit Lattice(double resolution) : resolution_(resolution), inv_resolution_(1.0 / resolution) {
    if (!(resolution > 0.0) || !std::isfinite(resolution) || !std::isfinite(inv_resolution_))
      throw std::invalid_argument("rtog::Lattice: resolution must be a positive finite number, got " +
                                  std::to_string(resolution));
  }

  double resolution() const { return resolution_; }

  /// Continuous lattice coordinate (cells as unit cubes).
  double toLattice(double world) const { return world * inv_resolution_; }
  Eigen::Vector3d toLattice(const Eigen::Vector3d& p) const { return p * inv_resolution_; }

  /// False when p is not finite or its cell lies outside the key range.
  bool tryKey(const Eigen::Vector3d& p, Key& out) const {
    const Eigen::Vector3d l = p * inv_resolution_;
    constexpr double lo = kKeyMin, hi = double{kKeyMax} + 1.0;
    if (!(l.x() >= lo && l.x() < hi && l.y() >= lo && l.y() < hi && l.z() >= lo && l.z() < hi)) return false;
    out = Key{floorToInt(l.x()), floorToInt(l.y()), floorToInt(l.z())};
    return true;
  }
  /// Throws std::out_of_range for points that have no key.
  Key key(const Eigen::Vector3d& p) const;

  Eigen::Vector3d cellCenter(const Key& k) const {
    return Eigen::Vector3d(k.x + 0.5, k.y + 0.5, k.z + 0.5) * resolution_;
  }
  Eigen::Vector3d boxMin(const Box& b) const { return Eigen::Vector3d(b.min.x, b.min.y, b.min.z) * resolution_; }
  Eigen::Vector3d boxMax(const Box& b) const {
    return Eigen::Vector3d(b.max.x + 1.0, b.max.y + 1.0, b.max.z + 1.0) * resolution_;
  }

 private:
  double resolution_;
  double inv_resolution_;
};

}  // namespace rtog
