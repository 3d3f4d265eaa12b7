// Covering a brick's cells with boxes: the greedy cover of bit masks that insertion, the planar
// cache and the class cover use; tests compare the cover of a single layer with the general one.
#pragma once

#include <array>
#include <cstdint>

#include "kernels/row_compare.hpp"
#include "storage/brick.hpp"

namespace rtog {
namespace detail {

// Covers the set bits of `mask` with disjoint boxes, greedily: from the lowest uncovered cell
// `start`, an x-run grown along y, then along z, over cells for which joins(start, cell) holds
// (every cell, when the mask is one class of fresh cells; an equal value, when a brick is
// rebuilt). emit(lo, hi, start) receives each box. A fresh 16^3 brick seen free becomes a
// handful of boxes instead of 4096 cells merged one by one.
template <class Joins, class Emit>
void coverGreedily(BrickMask m, Joins&& joins, Emit&& emit) {
  // Row (y, z) holds the 16 x-bits of word (y + 16 z) / 4 at bit 16 * (y % 4).
  const auto row = [&](int y, int z) {
    const int r = y + kBrickSize * z;
    return static_cast<std::uint32_t>((m[static_cast<std::size_t>(r >> 2)] >> ((r & 3) * kBrickSize)) & 0xFFFFu);
  };
  const auto clear = [&](int y, int z, std::uint32_t run) {
    const int r = y + kBrickSize * z;
    m[static_cast<std::size_t>(r >> 2)] &= ~(std::uint64_t{run} << ((r & 3) * kBrickSize));
  };
  for (int w = 0; w < kBrickWords; ++w)
    while (m[static_cast<std::size_t>(w)] != 0) {
      const int b = __builtin_ctzll(m[static_cast<std::size_t>(w)]);
      const int start = w * 64 + b;
      const int r = start >> kBrickBits, y = r & (kBrickSize - 1), z = r >> kBrickBits;
      const int x0 = b & (kBrickSize - 1);
      const int len = __builtin_ctz(~(row(y, z) >> x0));  // bits above the row are zero: len <= 16 - x0
      int x1 = x0;
      while (x1 + 1 < x0 + len && joins(start, start + (x1 + 1 - x0))) ++x1;
      const std::uint32_t run = xRun(x0, x1);
      const auto rowJoins = [&](int yy, int zz) {
        if ((row(yy, zz) & run) != run) return false;
        const int base = localIndex(0, yy, zz);
        for (int x = x0; x <= x1; ++x)
          if (!joins(start, base + x)) return false;
        return true;
      };
      int y1 = y;
      while (y1 + 1 < kBrickSize && rowJoins(y1 + 1, z)) ++y1;
      int z1 = z;
      for (bool grow = true; grow && z1 + 1 < kBrickSize;) {
        for (int yy = y; yy <= y1 && grow; ++yy) grow = rowJoins(yy, z1 + 1);
        if (grow) ++z1;
      }
      for (int zz = z; zz <= z1; ++zz)
        for (int yy = y; yy <= y1; ++yy) clear(yy, zz, run);
      const auto u8 = [](int c) { return static_cast<std::uint8_t>(c); };
      const std::uint8_t lo[3] = {u8(x0), u8(y), u8(z)}, hi[3] = {u8(x1), u8(y1), u8(z1)};
      emit(lo, hi, start);
    }
}

// coverGreedily's boxes (the same, in the same order) where joins(start, cell) is "the cell's
// value equals the start's, which is mergeable": a brick covered anew from a dense table of
// values (kBrickCells, by local index). Runs, rows and layers are grown by masks of the cells
// equal to the start value, a row's worth compared at once, instead of cell by cell.
template <class T, class Mergeable, class Emit>
void coverValues(BrickMask m, const T* values, Mergeable&& mergeable, Emit&& emit) {
  // Row r = y + 16 z holds the 16 x-bits of word r / 4 at bit 16 * (r % 4); its values start at 16 r.
  const auto row = [&](int r) {
    return static_cast<std::uint32_t>((m[static_cast<std::size_t>(r >> 2)] >> ((r & 3) * kBrickSize)) & 0xFFFFu);
  };
  const auto u8 = [](int c) { return static_cast<std::uint8_t>(c); };
  for (int w = 0; w < kBrickWords; ++w)
    while (m[static_cast<std::size_t>(w)] != 0) {
      const int b = __builtin_ctzll(m[static_cast<std::size_t>(w)]);
      const int start = w * 64 + b;
      const int r = start >> kBrickBits, y = r & (kBrickSize - 1), z = r >> kBrickBits;
      const int x0 = b & (kBrickSize - 1);
      const T v = values[start];
      int x1 = x0, y1 = y, z1 = z;
      if (mergeable(v)) {
        const auto same = [&](int yy, int zz) {
          const int rr = yy + kBrickSize * zz;
          return row(rr) & equalMask16(values + rr * kBrickSize, v);
        };
        x1 = x0 + __builtin_ctz(~((same(y, z) | (1u << x0)) >> x0)) - 1;
        const std::uint32_t run = xRun(x0, x1);
        while (y1 + 1 < kBrickSize && (same(y1 + 1, z) & run) == run) ++y1;
        for (bool grow = true; grow && z1 + 1 < kBrickSize;) {
          for (int yy = y; yy <= y1 && grow; ++yy) grow = (same(yy, z1 + 1) & run) == run;
          if (grow) ++z1;
        }
      }
      const std::uint64_t run = xRun(x0, x1);
      for (int zz = z; zz <= z1; ++zz)
        for (int yy = y; yy <= y1; ++yy) {
          const int rr = yy + kBrickSize * zz;
          m[static_cast<std::size_t>(rr >> 2)] &= ~(run << ((rr & 3) * kBrickSize));
        }
      const std::uint8_t lo[3] = {u8(x0), u8(y), u8(z)}, hi[3] = {u8(x1), u8(y1), u8(z1)};
      emit(lo, hi, start);
    }
}

// coverGreedily's boxes for a brick whose only cells to cover are one z-layer of values (a
// planar cache layer, in floats or in the int8 codes of a step rule): runs and rows are grown
// by masks of the cells equal to the start value, a row's worth compared at once, instead of
// cell by cell.
template <class T, class Mergeable, class Emit>
void coverLayer(const LayerMask& known, const T* values, int z, Mergeable&& mergeable, Emit&& emit) {
  std::uint32_t rows[kBrickSize];
  for (int y = 0; y < kBrickSize; ++y)
    rows[y] = static_cast<std::uint32_t>(known[static_cast<std::size_t>(y >> 2)] >> ((y & 3) * kBrickSize)) & 0xFFFFu;
  const auto equalTo = [values](int y, T v) { return equalMask16(values + y * kBrickSize, v); };
  const auto u8 = [](int c) { return static_cast<std::uint8_t>(c); };
  for (int y = 0; y < kBrickSize; ++y)
    while (rows[y] != 0) {
      const int x0 = __builtin_ctz(rows[y]);
      const T v = values[y * kBrickSize + x0];
      int x1 = x0, y1 = y;
      if (mergeable(v)) {
        const std::uint32_t same = (rows[y] & equalTo(y, v)) | (1u << x0);
        x1 = x0 + __builtin_ctz(~(same >> x0)) - 1;
        const std::uint32_t run = xRun(x0, x1);
        while (y1 + 1 < kBrickSize && (rows[y1 + 1] & equalTo(y1 + 1, v) & run) == run) ++y1;
      }
      const std::uint32_t run = xRun(x0, x1);
      for (int yy = y; yy <= y1; ++yy) rows[yy] &= ~run;
      const std::uint8_t lo[3] = {u8(x0), u8(y), u8(z)}, hi[3] = {u8(x1), u8(y1), u8(z)};
      emit(lo, hi, v);
    }
}

}  // namespace detail
}  // namespace rtog
