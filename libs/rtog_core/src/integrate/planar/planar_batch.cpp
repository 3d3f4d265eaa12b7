#include "integrate/planar/planar_batch.hpp"

#include <algorithm>
#include <cstddef>
#include <type_traits>

namespace rtog {

void PlanarBatch::reset(const Key& lo, const Key& hi) {
  bx0_ = lo.x >> kBrickBits;
  by0_ = lo.y >> kBrickBits;
  width_ = (hi.x >> kBrickBits) - bx0_ + 1;
  tiles_.assign(tilesFor(lo, hi), Tile{});
  columns_.assign(tiles_.size(), ColumnTile{});
}

void PlanarBatch::finalize() {
  for (std::size_t t = 0; t < columns_.size(); ++t) {
    std::array<std::uint64_t, kLayerWords>& marks = columns_[t].free;
    if ((marks[0] | marks[1] | marks[2] | marks[3]) == 0) continue;
    // A 16 x 16 bit transpose by swapping the off-diagonal blocks of 8, 4, 2 and 1 rows (of
    // 16 bits, four to a word: rows 8 and 4 apart are in other words, 2 and 1 apart in the same).
    std::uint64_t w[kLayerWords] = {marks[0], marks[1], marks[2], marks[3]};
    const auto acrossWords = [](std::uint64_t& a, std::uint64_t& b, int j, std::uint64_t low) {
      const std::uint64_t swap = ((a >> j) ^ b) & low;
      a ^= swap << j;
      b ^= swap;
    };
    acrossWords(w[0], w[2], 8, 0x00FF00FF00FF00FFull);
    acrossWords(w[1], w[3], 8, 0x00FF00FF00FF00FFull);
    acrossWords(w[0], w[1], 4, 0x0F0F0F0F0F0F0F0Full);
    acrossWords(w[2], w[3], 4, 0x0F0F0F0F0F0F0F0Full);
    for (std::uint64_t& word : w) {
      // Rows 2 apart: lanes 0, 1 with lanes 2, 3; then rows 1 apart: lanes 0, 2 with lanes 1, 3.
      std::uint64_t swap = ((word >> 2) ^ (word >> 32)) & 0x0000000033333333ull;
      word ^= (swap << 2) | (swap << 32);
      swap = ((word >> 1) ^ (word >> 16)) & 0x0000555500005555ull;
      word ^= (swap << 1) | (swap << 16);
    }
    for (std::size_t i = 0; i < kLayerWords; ++i) tiles_[t].free[i] |= w[i];
    marks.fill(0);
  }
}

namespace {

// Marks a walk's runs in a planar batch's tiles, moving from tile to tile by pointer steps:
// along the major axis a run is a mask in one row of a Tile (kRows) or of a ColumnTile.
template <bool kRows, int kMajorDir, int kMinorDir>
struct RunMarker {
  using Tile = std::conditional_t<kRows, PlanarBatch::Tile, PlanarBatch::ColumnTile>;
  Tile* tile;
  std::ptrdiff_t tile_step[2];  // to the next tile along the major and the minor axis
  int local[2];                 // the current cell in its tile, major and minor axis
  // `len` + 1 cells from the current one on along the major axis; ends on the last of them.
  void run(int len) {
    constexpr int m = kBrickSize - 1;
    for (;;) {
      // Cells left in this tile after the current one, in the direction of the run.
      const int room = kMajorDir > 0 ? m - local[0] : local[0];
      const int n = std::min(len, room);
      const int first = kMajorDir > 0 ? local[0] : local[0] - n;
      const unsigned cells = ((2u << n) - 1) << first;
      tile->free[static_cast<std::size_t>(local[1] >> 2)] |= std::uint64_t{cells} << ((local[1] & 3) * kBrickSize);
      local[0] += kMajorDir * n;
      len -= n;
      if (len == 0) return;
      // On into the next tile.
      tile += tile_step[0];
      local[0] = kMajorDir > 0 ? 0 : m;
      --len;
    }
  }
  void stepMinor() {
    local[1] += kMinorDir;
    if (local[1] & ~(kBrickSize - 1)) {
      local[1] &= kBrickSize - 1;
      tile += tile_step[1];
    }
  }
};

template <bool kRows, int kMajorDir, int kMinorDir>
void markRuns(const PlanarSegment& seg, typename RunMarker<kRows, kMajorDir, kMinorDir>::Tile* tile,
              std::ptrdiff_t width, const Key& from_key, std::int64_t skip_runs) {
  constexpr int m = kBrickSize - 1;
  const std::int64_t major_n = kRows ? seg.nx : seg.ny, minor_n = kRows ? seg.ny : seg.nx;
  const std::ptrdiff_t step_x = seg.sx, step_y = seg.sy * width;
  const int major_key = kRows ? from_key.x : from_key.y, minor_key = kRows ? from_key.y : from_key.x;
  if (minor_n == 0) {
    RunMarker<kRows, kMajorDir, kMinorDir> marker{
        tile, {kRows ? step_x : step_y, kRows ? step_y : step_x}, {major_key & m, minor_key & m}};
    if (major_n > 0) marker.run(static_cast<int>(major_n - 1));
    return;
  }
  // Run r ends at the count of major boundaries crossed before minor boundary r + 1, from the
  // exact crossing times: floor(((r + 1) one major_d + major_0 minor_d - minor_0 major_d - t) / (one minor_d)),
  // t = 0 for rows and 1 for columns (a tie goes to x: it ends a row and begins a column).
  const std::int64_t one = std::int64_t{1} << seg.shift;
  const std::int64_t major_d = kRows ? seg.dx : seg.dy, minor_d = kRows ? seg.dy : seg.dx;
  const std::int64_t major_0 = kRows ? seg.x0 : seg.y0, minor_0 = kRows ? seg.y0 : seg.x0;
  const std::int64_t den = one * minor_d, add = one * major_d;
  const std::int64_t num = add + major_0 * minor_d - minor_0 * major_d - (kRows ? 0 : 1);
  const std::int64_t add_q = add / den, add_r = add % den;
  // Start at run `skip`: its first cell is where run skip - 1 ended (a product of up to
  // 2^62 by the run count needs 128 bits).
  const std::int64_t skip = std::min(skip_runs, minor_n);
  std::int64_t start = 0, q = num / den, rem = num % den;
  if (skip > 0) {
    __extension__ using Wide = __int128;
    start = std::min(static_cast<std::int64_t>((Wide{num} + Wide{add} * (skip - 1)) / den), major_n);
    const Wide at_skip = Wide{num} + Wide{add} * skip;
    q = static_cast<std::int64_t>(at_skip / den);
    rem = static_cast<std::int64_t>(at_skip % den);
  }
  const int major_cell = major_key + kMajorDir * static_cast<int>(start);
  const int minor_cell = minor_key + kMinorDir * static_cast<int>(skip);
  const std::ptrdiff_t tiles_major = (major_cell >> kBrickBits) - (major_key >> kBrickBits);
  const std::ptrdiff_t tiles_minor = (minor_cell >> kBrickBits) - (minor_key >> kBrickBits);
  RunMarker<kRows, kMajorDir, kMinorDir> marker{
      tile + (kRows ? tiles_major + tiles_minor * width : tiles_minor + tiles_major * width),
      {kRows ? step_x : step_y, kRows ? step_y : step_x},
      {major_cell & m, minor_cell & m}};
  for (std::int64_t r = skip; r < minor_n; ++r) {
    const std::int64_t end = std::min(q, major_n);
    marker.run(static_cast<int>(end - start));
    marker.stepMinor();
    start = end;
    // Without a branch: the carry comes as irregularly as a line's steps.
    rem += add_r;
    const std::int64_t carry = rem >= den;
    rem -= den & -carry;
    q += add_q + carry;
  }
  if (start < major_n) marker.run(static_cast<int>(major_n - 1 - start));
}

}  // namespace

void PlanarBatch::markRayFree(const PlanarSegment& seg, const Key& from_key, std::int64_t skip_runs) {
  // walkPlanar's cells as runs: along the axis that steps more, the walk's cells in each row
  // (or column) of the other are one run, whose end follows from the exact crossing times by
  // an integer division carried from run to run (as in run-slice line drawing).
  if (seg.nx + seg.ny == 0) return;
  const std::size_t at = tileIndex(from_key.x, from_key.y);
  Tile* tile = &tiles_[at];
  ColumnTile* column = &columns_[at];
  // One loop per orientation and direction: the directions are constants in the loop.
  const int major_s = seg.nx >= seg.ny ? seg.sx : seg.sy, minor_s = seg.nx >= seg.ny ? seg.sy : seg.sx;
  const int variant = (seg.nx >= seg.ny ? 4 : 0) + (major_s > 0 ? 2 : 0) + (minor_s > 0 ? 1 : 0);
  switch (variant) {
    case 0: markRuns<false, -1, -1>(seg, column, width_, from_key, skip_runs); break;
    case 1: markRuns<false, -1, 1>(seg, column, width_, from_key, skip_runs); break;
    case 2: markRuns<false, 1, -1>(seg, column, width_, from_key, skip_runs); break;
    case 3: markRuns<false, 1, 1>(seg, column, width_, from_key, skip_runs); break;
    case 4: markRuns<true, -1, -1>(seg, tile, width_, from_key, skip_runs); break;
    case 5: markRuns<true, -1, 1>(seg, tile, width_, from_key, skip_runs); break;
    case 6: markRuns<true, 1, -1>(seg, tile, width_, from_key, skip_runs); break;
    default: markRuns<true, 1, 1>(seg, tile, width_, from_key, skip_runs); break;
  }
}

}  // namespace rtog
