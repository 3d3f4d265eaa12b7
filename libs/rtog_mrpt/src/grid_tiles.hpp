// Private to librtog_mrpt: the 2D view of a map in the mrpt_grid preset as copy-on-write tiles
// of MRPT cells, with the likelihood field's terms beside them. Copies of a map (the particles of
// rbpf-slam) share their tiles; a scan inserted into one copy clones the tiles it steps and drops
// the terms near them, so that no operation on the likelihood path costs O(map) per scan, and a
// copy costs a pointer per tile.
//
// Tiles are aligned to the lattice (key / 32), not to the grid's cells, so that a grid that grows
// (MRPT's resizeGrid moves its origin) keeps every tile. The array of tile pointers is shared too:
// a copy costs a few pointers, and its first change clones the array.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "likelihood_field_2d.hpp"
#include "rtog/mrpt/map_types.h"
#include "util/cow_ptr.hpp"

namespace rtog {

class GridTiles {
 public:
  static constexpr int kBits = 5, kSide = 1 << kBits;
  static constexpr std::size_t kCells = std::size_t{kSide} * kSide;

  /// All cells unknown, on the grid `frame`.
  explicit GridTiles(const TGridFrame2D& frame);
  const TGridFrame2D& frame() const { return frame_; }
  /// Moves to the geometry of `frame` (a grown grid), keeping the tiles it still covers.
  void setFrame(const TGridFrame2D& frame);

  /// The cell at grid indices (cx, cy), which must lie in the grid.
  std::int8_t cell(int cx, int cy) const {
    const Tile& t = (*tiles_)[tileAt(cx, cy)];
    return t.cells ? t.cells->v[inTile(cx, cy)] : std::int8_t{0};
  }
  /// Sets the cell of lattice column (kx, ky), which must lie in the grid.
  void setCell(std::int32_t kx, std::int32_t ky, std::int8_t v);
  /// Drops the kept terms that the cells set since the last call may have changed.
  void dropStaleTerms(int window);
  /// Sets every cell from a dense row-major array of the grid's size (a view of the map), and
  /// drops every kept term.
  void loadDense(const std::int8_t* dense);

  /// lmLikelihoodField_Thrun of a planar scan on these cells, as the stock grid computes it on
  /// the same cells (fieldScanLogLikelihood). Terms are kept if the options' enableLikelihoodCache.
  double scanLogLikelihood(const FieldGrid& g, const mrpt::obs::CObservation2DRangeScan& scan,
                           const mrpt::poses::CPose3D& pose);


 private:
  struct Cells {
    std::array<std::int8_t, kCells> v{};
  };
  /// Per cell the kept squared distance (FieldConstants units) to the nearest occupied cell.
  struct Terms {
    static constexpr std::uint16_t kNone = 0xFFFF;
    Terms() { best.fill(kNone); }
    std::array<std::uint16_t, kCells> best;
  };
  struct Tile {
    detail::CowPtr<Cells> cells{nullptr};
    detail::CowPtr<Terms> terms{nullptr};
  };
  static std::int32_t tileCoord(std::int32_t k) { return k >= 0 ? k >> kBits : -((-k + kSide - 1) >> kBits); }
  static std::size_t within(std::int32_t kx, std::int32_t ky) {
    return static_cast<std::size_t>(((ky - tileCoord(ky) * kSide) << kBits) + (kx - tileCoord(kx) * kSide));
  }
  std::size_t tileOf(std::int32_t kx, std::int32_t ky) const {
    return static_cast<std::size_t>(tileCoord(ky) - ty0_) * static_cast<std::size_t>(ntx_) +
           static_cast<std::size_t>(tileCoord(kx) - tx0_);
  }
  // Grid cell (cx, cy), cx, cy >= 0: its tile and its index in the tile, without a floor division
  // (the grid's first tile starts ux0_, uy0_ cells before the grid).
  std::size_t tileAt(int cx, int cy) const {
    return static_cast<std::size_t>((cy + uy0_) >> kBits) * static_cast<std::size_t>(ntx_) +
           static_cast<std::size_t>((cx + ux0_) >> kBits);
  }
  static constexpr int kMask = kSide - 1;
  std::size_t inTile(int cx, int cy) const {
    return static_cast<std::size_t>((((cy + uy0_) & kMask) << kBits) | ((cx + ux0_) & kMask));
  }
  /// The kept term of each distance, for the options they were kept with.
  void useOptions(const FieldConstants& f, bool logs);

  TGridFrame2D frame_;
  std::int32_t ox_ = 0, oy_ = 0;    // lattice key of grid cell (0, 0)
  std::int32_t tx0_ = 0, ty0_ = 0;  // first tile
  std::int32_t ntx_ = 0, nty_ = 0;  // tiles across, up
  std::int32_t ux0_ = 0, uy0_ = 0;  // cells of the first tile before the grid's first
  /// The tiles, row by row; the array itself is shared by copies until one changes a tile.
  detail::CowPtr<std::vector<Tile>> tiles_{nullptr};
  std::vector<std::uint32_t> changed_;  // tiles whose cells were set since dropStaleTerms()
  // What the kept distances were computed with, and the term of each distance.
  std::optional<FieldConstants> field_;
  bool logs_ = true;
  std::vector<double> value_of_best_;
};

}  // namespace rtog
