// The update set of a planar scan (all cells in one z-layer) and its beams in exact form.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "storage/brick.hpp"

namespace rtog {

/// A beam of a planar scan in the exact form a PlanarBatch walks.
struct PlanarBeam {
  PlanarSegment seg;
  Key end;
  bool traced = false;          ///< false for a beam skipped as bad input
  bool hit = false;
  std::int64_t skip_runs = 0;  ///< leading runs other beams of the scan are known to mark
};

/// The update set of a planar scan, whose cells all lie in one z-layer: the layer masks of the
/// bricks under the scan's bounding box in a dense grid, found by arithmetic instead of a hash.
class PlanarBatch {
 public:
  struct Tile {
    std::array<std::uint64_t, kLayerWords> occupied, free;  ///< bit (y % 16) * 16 + x % 16
  };
  /// Free marks of walks that step more along y, transposed: bit (x % 16) * 16 + y % 16, so that
  /// a run in a column is one mask in one word, as a run in a row is in a Tile.
  struct ColumnTile {
    std::array<std::uint64_t, kLayerWords> free;
  };
  /// Bricks a batch over cells [lo, hi] (x and y) would hold.
  static std::size_t tilesFor(const Key& lo, const Key& hi) {
    return static_cast<std::size_t>((hi.x >> kBrickBits) - (lo.x >> kBrickBits) + 1) *
           static_cast<std::size_t>((hi.y >> kBrickBits) - (lo.y >> kBrickBits) + 1);
  }
  /// Starts an empty batch over cells [lo, hi]; z is not looked at.
  void reset(const Key& lo, const Key& hi);
  bool markOccupied(const Key& k) {
    const int i = bitOf(k.x, k.y);
    std::uint64_t& w = tileOf(k.x, k.y).occupied[static_cast<std::size_t>(i >> 6)];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    const bool fresh = (w & bit) == 0;
    w |= bit;
    return fresh;
  }
  void markRayFree(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Key& from_key, const Key& to_key) {
    markRayFree(planarSegment(from, to, from_key, to_key), from_key, 0);
  }
  /// Marks the walk of `seg` from cell `from_key`, leaving out its first `skip_runs` runs (rows
  /// if it steps more along x, else columns; never the last).
  void markRayFree(const PlanarSegment& seg, const Key& from_key, std::int64_t skip_runs);
  /// Folds the column marks into tiles(); call after the last markRayFree.
  void finalize();

  int brickX0() const { return bx0_; }
  int brickY0() const { return by0_; }
  int width() const { return width_; }  ///< bricks along x
  const std::vector<Tile>& tiles() const { return tiles_; }
  std::size_t memoryBytes() const { return tiles_.capacity() * sizeof(Tile) + columns_.capacity() * sizeof(ColumnTile); }

 private:
  static int bitOf(int x, int y) { return (x & (kBrickSize - 1)) | ((y & (kBrickSize - 1)) << kBrickBits); }
  std::size_t tileIndex(int x, int y) const {
    return static_cast<std::size_t>(((y >> kBrickBits) - by0_) * width_ + ((x >> kBrickBits) - bx0_));
  }
  Tile& tileOf(int x, int y) { return tiles_[tileIndex(x, y)]; }
  int bx0_ = 0, by0_ = 0, width_ = 0;
  std::vector<Tile> tiles_;
  std::vector<ColumnTile> columns_;  // indexed as tiles_
};

}  // namespace rtog
