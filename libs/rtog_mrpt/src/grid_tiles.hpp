// Private to librtog_mrpt: the 2D view of a map in the mrpt_grid preset as copy-on-write tiles
// of what the likelihood field reads of MRPT's cells, whether each is occupied (one bit), with
// the field's terms beside them. Copies of a map (the particles of rbpf-slam) share their tiles;
// a scan inserted into one copy clones only the tiles where it turned a cell occupied or not
// occupied, and drops the terms near them, so that no operation on the likelihood path costs
// O(map) per scan, and a copy costs a pointer per tile. A scan's steps change many cells' values
// but few cells' side of the threshold: the tiles copies clone are few, and 1/8 of the cells'.
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

  /// Sets the cell of lattice column (kx, ky), which must lie in the grid, to MRPT cell value v.
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
  /// Per row of the tile, bit x: whether cell x is occupied (occupiedBelow()).
  struct Occupied {
    std::array<std::uint32_t, kSide> rows{};
  };
  static_assert(kSide == 32, "a row of a tile is one word");
  /// Per cell the kept squared distance (FieldConstants units) to the nearest occupied cell.
  struct Terms {
    static constexpr std::uint16_t kNone = 0xFFFF;
    Terms() { best.fill(kNone); }
    std::array<std::uint16_t, kCells> best;
  };
  struct Tile {
    detail::CowPtr<Occupied> occupied{nullptr};
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
  /// Sets the bit of cell `i` (its index in the tile) of tile `t` to `occupied`.
  void setOccupied(std::size_t t, std::size_t i, bool occupied);
  /// The kept term of each distance, for the options they were kept with.
  void useOptions(const FieldConstants& f, bool logs);

  TGridFrame2D frame_;
  std::int32_t ox_ = 0, oy_ = 0;    // lattice key of grid cell (0, 0)
  std::int32_t tx0_ = 0, ty0_ = 0;  // first tile
  std::int32_t ntx_ = 0, nty_ = 0;  // tiles across, up
  std::int32_t ux0_ = 0, uy0_ = 0;  // cells of the first tile before the grid's first
  /// The tiles, row by row; the array itself is shared by copies until one changes a tile.
  detail::CowPtr<std::vector<Tile>> tiles_{nullptr};
  std::vector<std::uint32_t> changed_;  // tiles whose bits changed since dropStaleTerms()
  float occupied_below_;                // occupiedBelow()
  // What the kept distances were computed with, and the term of each distance.
  std::optional<FieldConstants> field_;
  bool logs_ = true;
  std::vector<double> value_of_best_;
};

}  // namespace rtog
