// Brick geometry: space is cut into aligned cubes of kBrickSize^3 cells. Bricks group a scan's
// updates and bound leaf cuboids, so that one scan's changes stay local. Cells of a brick are
// named by one local index, x fastest; a z-layer is kLayerCells consecutive indices.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "rtog/core/key.hpp"  // kBrickBits

namespace rtog {

constexpr int kBrickSize = 1 << kBrickBits;
constexpr int kBrickCells = kBrickSize * kBrickSize * kBrickSize;
constexpr int kBrickWords = kBrickCells / 64;
/// A brick's z-layer: kBrickSize^2 cells, local indices z * kLayerCells + (0 .. kLayerCells).
constexpr int kLayerCells = kBrickSize * kBrickSize;
constexpr int kLayerWords = kLayerCells / 64;

/// A bit per local cell index.
using BrickMask = std::array<std::uint64_t, kBrickWords>;
using LayerMask = std::array<std::uint64_t, kLayerWords>;

inline Key brickOf(const Key& k) {
  // Arithmetic shift: floor division for negative keys too.
  return Key{k.x >> kBrickBits, k.y >> kBrickBits, k.z >> kBrickBits};
}
inline Key brickOrigin(const Key& brick) {
  return Key{brick.x * kBrickSize, brick.y * kBrickSize, brick.z * kBrickSize};
}
/// The local index of brick-local cell (x, y, z), each in [0, kBrickSize).
inline int localIndex(int x, int y, int z) { return x | (y << kBrickBits) | (z << (2 * kBrickBits)); }
/// The local index of a cell in its brick.
inline int localIndex(const Key& k) {
  constexpr int m = kBrickSize - 1;
  return localIndex(k.x & m, k.y & m, k.z & m);
}
inline Key localKey(int index) {
  constexpr int m = kBrickSize - 1;
  return Key{index & m, (index >> kBrickBits) & m, (index >> (2 * kBrickBits)) & m};
}

/// Bits lo..hi of a 16-cell x-row.
inline std::uint32_t xRun(int lo, int hi) { return ((std::uint32_t{1} << (hi - lo + 1)) - 1u) << lo; }

/// A box of brick-local cells, inclusive, in bytes: the leaf level's 12-byte entries hold one.
struct LocalBox {
  std::uint8_t lo[3], hi[3];

  bool isCell() const { return lo[0] == hi[0] && lo[1] == hi[1] && lo[2] == hi[2]; }
  bool contains(const Key& local) const {
    return local.x >= lo[0] && local.x <= hi[0] && local.y >= lo[1] && local.y <= hi[1] && local.z >= lo[2] &&
           local.z <= hi[2];
  }
  /// The box in global cells, for a brick whose first cell is `origin`.
  Box global(const Key& origin) const {
    return Box{Key{origin.x + lo[0], origin.y + lo[1], origin.z + lo[2]},
               Key{origin.x + hi[0], origin.y + hi[1], origin.z + hi[2]}};
  }
  /// Calls fn(local index) for every cell, x fastest.
  template <class Fn>
  void forEachCell(Fn&& fn) const {
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) fn(localIndex(x, y, z));
  }
  /// Calls fn(local index of the row's first cell x = 0, x-run bits) for every x-row.
  template <class Fn>
  void forEachRow(Fn&& fn) const {
    const std::uint64_t run = xRun(lo[0], hi[0]);
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y) fn(localIndex(0, y, z), run);
  }
  /// Sets the box's bits in `mask`.
  void paint(BrickMask& mask) const {
    forEachRow([&](int base, std::uint64_t run) { mask[static_cast<std::size_t>(base >> 6)] |= run << (base & 63); });
  }
};

inline std::size_t popcount64(std::uint64_t w) {
  // SWAR count: the baseline x86-64 target has no POPCNT instruction.
  w = w - ((w >> 1) & 0x5555555555555555ull);
  w = (w & 0x3333333333333333ull) + ((w >> 2) & 0x3333333333333333ull);
  w = (w + (w >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<std::size_t>((w * 0x0101010101010101ull) >> 56);
}

inline std::size_t maskPopcount(const BrickMask& words) {
  std::size_t n = 0;
  for (const std::uint64_t w : words) n += popcount64(w);
  return n;
}

}  // namespace rtog
