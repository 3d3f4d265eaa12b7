// One scan's cells of the mrpt_grid preset while its beams step them, as the grids' int8 cells:
// blocks of 8^3 cells made on first touch from the map's leaves there, so that a beam's steps
// cost an array update (a block lookup each 8 cells or so) and a cell's steps stay in beam
// order; then written back through OccupancyMap::assignCells. Used where a scan's steps are not
// the 2D grid's whole steps in one layer (those go through the planar cache): COccupancyGridMap3D's
// rays (mrpt_grid3d.hpp) and the graded steps of the estimator's models (grid_graded.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "mrpt_grid.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "util/flat_hash_map.hpp"

namespace rtog::mrpt_grid {

/// Cells are addressed by (cx, cy, cz) >= 0 from `offset` (the lattice key of cell 0).
class ScanCells {
 public:
  ScanCells(const OccupancyMap& map, const Key& offset) : map_(map), offset_(offset) {}

  /// The cell, marked as stepped (it is written back).
  std::int8_t& at(int cx, int cy, int cz) {
    Block& b = block(cx, cy, cz);
    const int i = indexOf(cx, cy, cz);
    b.seen[static_cast<std::size_t>(i) >> 6] |= std::uint64_t{1} << (i & 63);
    return b.v[static_cast<std::size_t>(i)];
  }
  /// The cell's value, not marked (0, the grid's unknown, where the map has no leaf).
  std::int8_t peek(int cx, int cy, int cz) { return block(cx, cy, cz).v[static_cast<std::size_t>(indexOf(cx, cy, cz))]; }

  /// The cells stepped, in lattice keys with their values: greedy boxes of equal cells within a
  /// block (x runs grown along y, then z), so that a brick first made by this scan does not hold
  /// a leaf per cell (assignCells takes a new brick's boxes as its leaves).
  void emit(std::vector<Box>& boxes, std::vector<float>& values) const {
    for (const Block& b : blocks_) {
      std::array<std::uint64_t, kCells / 64> open = b.seen;  // stepped, not yet in a box
      const auto isOpen = [&](int i) { return ((open[static_cast<std::size_t>(i) >> 6] >> (i & 63)) & 1u) != 0; };
      const auto at = [](int x, int y, int z) { return (z << (2 * kBits)) | (y << kBits) | x; };
      for (int i = 0; i < kCells; ++i) {
        if (!isOpen(i)) continue;
        const int x0 = i & kMask, y0 = (i >> kBits) & kMask, z0 = i >> (2 * kBits);
        const std::int8_t v = b.v[static_cast<std::size_t>(i)];
        const auto same = [&](int x, int y, int z) { return isOpen(at(x, y, z)) && b.v[static_cast<std::size_t>(at(x, y, z))] == v; };
        int x1 = x0, y1 = y0, z1 = z0;
        while (x1 + 1 < kSide && same(x1 + 1, y0, z0)) ++x1;
        const auto rowSame = [&](int y, int z) {
          for (int x = x0; x <= x1; ++x)
            if (!same(x, y, z)) return false;
          return true;
        };
        while (y1 + 1 < kSide && rowSame(y1 + 1, z0)) ++y1;
        const auto sliceSame = [&](int z) {
          for (int y = y0; y <= y1; ++y)
            if (!rowSame(y, z)) return false;
          return true;
        };
        while (z1 + 1 < kSide && sliceSame(z1 + 1)) ++z1;
        for (int z = z0; z <= z1; ++z)
          for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
              const int c = at(x, y, z);
              open[static_cast<std::size_t>(c) >> 6] &= ~(std::uint64_t{1} << (c & 63));
            }
        boxes.push_back(Box{Key{b.x0 + x0, b.y0 + y0, b.z0 + z0}, Key{b.x0 + x1, b.y0 + y1, b.z0 + z1}});
        values.push_back(mrpt_grid::valueOfCell(v));
      }
    }
  }

  /// Writes the stepped cells back into `map` (emit(), then OccupancyMap::assignCells).
  InsertStats writeBack(OccupancyMap& map) const {
    std::vector<Box> boxes;
    std::vector<float> values;
    emit(boxes, values);
    return boxes.empty() ? InsertStats{} : map.assignCells(boxes.data(), values.data(), boxes.size());
  }

 private:
  static constexpr int kBits = 3, kSide = 1 << kBits, kMask = kSide - 1, kCells = kSide * kSide * kSide;
  struct Block {
    std::int32_t x0, y0, z0;  // lattice key of its first cell
    std::array<std::int8_t, kCells> v;
    std::array<std::uint64_t, kCells / 64> seen;
  };
  static int indexOf(int cx, int cy, int cz) {
    return ((cz & kMask) << (2 * kBits)) | ((cy & kMask) << kBits) | (cx & kMask);
  }
  Block& block(int cx, int cy, int cz) {
    const std::uint64_t key = std::uint64_t(unsigned(cx) >> kBits) | std::uint64_t(unsigned(cy) >> kBits) << 21 |
                              std::uint64_t(unsigned(cz) >> kBits) << 42;
    if (key != last_key_) {
      const auto next = static_cast<std::uint32_t>(blocks_.size());
      const std::uint32_t b = index_.findOrInsert(key, next);
      if (b == next) make(cx >> kBits, cy >> kBits, cz >> kBits);
      last_ = &blocks_[b];
      last_key_ = key;
    }
    return *last_;
  }
  void make(int bx, int by, int bz) {
    Block& b = blocks_.emplace_back();
    b.x0 = offset_.x + bx * kSide, b.y0 = offset_.y + by * kSide, b.z0 = offset_.z + bz * kSide;
    b.v.fill(0);  // unknown: the grid's 0.5
    b.seen.fill(0);
    last_key_ = ~std::uint64_t{0};  // emplace_back may have moved the blocks
    const Box region{Key{b.x0, b.y0, b.z0}, Key{b.x0 + kMask, b.y0 + kMask, b.z0 + kMask}};
    map_.forEachLeafIn(region, [&](const Box& leaf, float value) {
      const auto c = static_cast<std::int8_t>(mrpt_grid::cellOfValue(value));
      for (std::int32_t z = std::max(leaf.min.z, region.min.z); z <= std::min(leaf.max.z, region.max.z); ++z)
        for (std::int32_t y = std::max(leaf.min.y, region.min.y); y <= std::min(leaf.max.y, region.max.y); ++y)
          for (std::int32_t x = std::max(leaf.min.x, region.min.x); x <= std::min(leaf.max.x, region.max.x); ++x)
            b.v[static_cast<std::size_t>(((z - b.z0) << (2 * kBits)) | ((y - b.y0) << kBits) | (x - b.x0))] = c;
    });
  }

  const OccupancyMap& map_;
  Key offset_;
  std::vector<Block> blocks_;
  detail::FlatHashMap64 index_;
  std::uint64_t last_key_ = ~std::uint64_t{0};
  Block* last_ = nullptr;
};

}  // namespace rtog::mrpt_grid
