// Incremental discovery on the map (the estimator seed, section 4) and occupancy as a field
// (section 1). Unknown space is where no leaf is, so a frontier (a free cell face-adjacent to
// unknown space) is found from the free leaves' faces: the part of a face that no neighbouring
// leaf covers, without expanding a merged cuboid into its cells. The field O(x) interpolates the
// cells' log-odds between their centres, unknown cells at the prior.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

/// Frontiers in 3D: the free cells with a face neighbour that is unknown (no leaf holds it; a
/// neighbour beyond the key range is not unknown space, the map cannot hold it). In 2D, the
/// columns of a height band as its 2D view shows them (band.hpp: a column is known if the band
/// holds a known cell of it, free if its highest log-odds is free): the free columns with a
/// 4-neighbour column that is unknown.
struct FrontierOptions {
  bool planar = false;                     ///< 2D (a height band) rather than 3D. (Default: false)
  double min_z = -1000.0, max_z = 1000.0;  ///< planar: the band [m]. (Default: all)
  /// Frontier regions smaller than this many cells are dropped (sensor speckle). (Default: 1)
  std::int64_t min_region_cells = 1;
};

/// The frontier cells as disjoint boxes, each inside one leaf (3D) or one row of columns of the
/// band (planar: z of the box is the band's z-range), in a deterministic order.
std::vector<Box> frontierCells(const OccupancyMap& map, const FrontierOptions& options = {});

/// A connected set of frontier cells (26-connected in 3D, 8-connected columns in 2D).
struct FrontierRegion {
  std::vector<Box> boxes;       ///< its cells (frontierCells' boxes, whole)
  std::int64_t cells = 0;       ///< cells (planar: columns)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mean of the cells' centres [m]
  /// The mean direction from its cells into the unknown: the sum of the unit normals of the
  /// cell faces that meet unknown space, normalized (zero if they cancel).
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

/// The frontier cells grouped into connected regions, largest first (ties: by first box). Throws
/// std::invalid_argument for min_z > max_z or min_region_cells < 1.
std::vector<FrontierRegion> frontierRegions(const OccupancyMap& map, const FrontierOptions& options = {});

/// The occupancy field at a point: log-odds interpolated between cell centres, trilinearly in 3D
/// (bilinearly between the band's columns in 2D), unknown cells at the prior l0; continuous
/// everywhere, equal to the cell's value at a cell centre.
struct FieldValue {
  double log_odds = 0.0;
  double probability = 0.5;
  /// d log_odds / d x [1/m]: the interpolant's gradient (one-sided where x lies on a cell-centre
  /// plane, where the interpolant has a kink: the side towards +infinity).
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
};

/// O(x) in 3D. A point without a key, or not finite, reads the prior with a zero gradient.
FieldValue occupancyAt(const OccupancyMap& map, const Eigen::Vector3d& x);
/// O(x, y) in the band [min_z, max_z] [m] (z of the gradient 0).
FieldValue occupancyAt2D(const OccupancyMap& map, const Eigen::Vector3d& x, double min_z, double max_z);

}  // namespace rtog
