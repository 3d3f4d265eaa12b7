// Maps split by space (doc/scale-out.md): a directory of tiles, each a core map file of the cells
// of one region (OccupancyMap::setRegion), and an index naming them with the map's resolution.
// The tiles of a partition hold together, leaf for leaf, the map one process builds.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rtog/core/occupancy_map.hpp"

namespace rtog {

class CRTreeOccupancyGridMap;

struct TileInfo {
  std::string file;  ///< relative to the directory
  Box region;        ///< inclusive keys, whole bricks
  std::size_t leaves = 0;
  std::int64_t cells = 0;
};

/// `DIR/tiles.index`: a text file, "rtog-tiles 1", then "resolution R", then one line a tile
/// "tile FILE x0 y0 z0 x1 y1 z1 LEAVES CELLS". Written last, by a rename: a directory without it
/// is not a map (a build that failed half-way).
struct TiledMapIndex {
  double resolution = 0.0;
  std::vector<TileInfo> tiles;

  static constexpr const char* kFile = "tiles.index";
  /// Throws std::runtime_error naming the file and line on a missing or malformed index.
  static TiledMapIndex read(const std::string& dir);
  void write(const std::string& dir) const;
};

/// True if `path` is a directory holding a tile index.
bool isTiledMap(const std::string& path);

/// Writes a tile (a map restricted to its region) as `dir/name` in the core format; its entry.
TileInfo writeTile(const OccupancyMap& tile, const std::string& dir, const std::string& name);

/// The tiles of `dir` that meet `region` (inclusive keys; Box::empty(): every tile) as one map:
/// their leaves, which lie in their tiles, put together (nothing else is read). Throws
/// std::runtime_error for a missing or damaged index or tile, or tiles of other parameters.
OccupancyMap loadTiles(const std::string& dir, const Box& region = Box::empty());

/// The neighbourhood of a robot in a large map: the tiles of `dir` meeting the box [lo, hi]
/// (metres) as the MRPT map type (octomap preset stating the tiles' rule, as wrapCoreMap).
std::shared_ptr<CRTreeOccupancyGridMap> loadTiledMap(const std::string& dir, const Eigen::Vector3d& lo,
                                                     const Eigen::Vector3d& hi);

/// A partition of the key space into `n` slabs across x (or y, whichever of the work's extents is
/// longer) of whole bricks, each holding about the same share of `work`: per brick column (x or y
/// brick coordinate -> work), e.g. the ray cells of a coarse first pass. The outer slabs reach
/// the ends of the key range. n >= 1.
std::vector<Box> balancedSlabs(const std::vector<std::pair<std::int32_t, double>>& work_x,
                               const std::vector<std::pair<std::int32_t, double>>& work_y, int n);

}  // namespace rtog
