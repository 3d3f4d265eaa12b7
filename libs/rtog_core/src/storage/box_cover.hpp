// Covering a brick's cells with boxes: the greedy cover of bit masks that insertion, the planar
// cache and the class cover use; tests compare each cover with a cell-by-cell greedy cover.
#pragma once

#include <array>
#include <cstdint>

#include "kernels/row_compare.hpp"
#include "storage/brick.hpp"

namespace rtog {
namespace detail {

// Covers the set bits of `m` with disjoint boxes, greedily: from the lowest uncovered cell
// `start`, an x-run grown along y, then along z, over the cells that may join start's box:
// joinable(row, start, y, z) returns those of row (y, z), given `row`, the row's uncovered
// cells (bit x for cell x). emit(lo, hi, start) receives each box. Rows are taken 16 cells at
// once, as masks.
template <class Joinable, class Emit>
void coverRows(BrickMask m, Joinable&& joinable, Emit&& emit) {
  // Row r = y + 16 z holds the 16 x-bits of word r / 4 at bit 16 * (r % 4).
  const auto row = [&](int y, int z) {
    const int r = y + kBrickSize * z;
    return static_cast<std::uint32_t>((m[static_cast<std::size_t>(r >> 2)] >> ((r & 3) * kBrickSize)) & 0xFFFFu);
  };
  const auto u8 = [](int c) { return static_cast<std::uint8_t>(c); };
  for (int w = 0; w < kBrickWords; ++w)
    while (m[static_cast<std::size_t>(w)] != 0) {
      const int b = __builtin_ctzll(m[static_cast<std::size_t>(w)]);
      const int start = w * 64 + b;
      const int r = start >> kBrickBits, y = r & (kBrickSize - 1), z = r >> kBrickBits;
      const int x0 = b & (kBrickSize - 1);
      const auto joins = [&](int yy, int zz) { return joinable(row(yy, zz), start, yy, zz); };
      // The start cell is in its box whatever joinable says of it; bits above the row are zero.
      const int x1 = x0 + __builtin_ctz(~((joins(y, z) | (1u << x0)) >> x0)) - 1;
      const std::uint32_t run = xRun(x0, x1);
      int y1 = y;
      while (y1 + 1 < kBrickSize && (joins(y1 + 1, z) & run) == run) ++y1;
      int z1 = z;
      for (bool grow = true; grow && z1 + 1 < kBrickSize;) {
        for (int yy = y; yy <= y1 && grow; ++yy) grow = (joins(yy, z1 + 1) & run) == run;
        if (grow) ++z1;
      }
      for (int zz = z; zz <= z1; ++zz)
        for (int yy = y; yy <= y1; ++yy) {
          const int rr = yy + kBrickSize * zz;
          m[static_cast<std::size_t>(rr >> 2)] &= ~(std::uint64_t{run} << ((rr & 3) * kBrickSize));
        }
      const std::uint8_t lo[3] = {u8(x0), u8(y), u8(z)}, hi[3] = {u8(x1), u8(y1), u8(z1)};
      emit(lo, hi, start);
    }
}

// The cells of `mask` covered with boxes (coverRows, every cell joining): a fresh 16^3 brick
// seen free becomes a handful of boxes instead of 4096 cells merged one by one.
template <class Emit>
void coverGreedily(const BrickMask& mask, Emit&& emit) {
  coverRows(mask, [](std::uint32_t row, int, int, int) { return row; }, emit);
}

// A brick covered anew from a dense table of values (kBrickCells, by local index): coverRows
// joining the cells equal to the start's value if that is mergeable, a row compared at once.
template <class T, class Mergeable, class Emit>
void coverValues(const BrickMask& mask, const T* values, Mergeable&& mergeable, Emit&& emit) {
  coverRows(
      mask,
      [&](std::uint32_t row, int start, int y, int z) -> std::uint32_t {
        const T v = values[start];
        if (row == 0 || !mergeable(v)) return 0;
        return row & equalMask16(values + (y + kBrickSize * z) * kBrickSize, v);
      },
      emit);
}

// coverValues' boxes for a brick whose only cells to cover are one z-layer of values (a
// planar cache layer, in floats or in the int8 codes of a step rule), on the layer's 4 mask
// words and 256 values alone; emit(lo, hi, value).
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
