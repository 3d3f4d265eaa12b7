// The frontier finders behind rtog/core/explore.hpp: each gives the frontier cells as disjoint
// boxes and, for the regions' normals, the pieces of cell faces that meet unknown space.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "rtog/core/explore.hpp"

namespace rtog::explore_detail {

/// Cells of the frontier sharing one direction into the unknown: `normal` is that unit normal
/// times the number of faces (cells) of the piece.
struct FrontierPiece {
  Box cells;
  Eigen::Vector3d normal;
};

/// The 3D frontier: boxes disjoint, each inside a free leaf.
void frontier3D(const OccupancyMap& map, std::vector<FrontierPiece>& pieces, std::vector<Box>& boxes);
/// The 2D frontier of the band `region` (bandRegion): boxes one row of columns each, z the band's.
void frontier2D(const OccupancyMap& map, const Box& region, std::vector<FrontierPiece>& pieces, std::vector<Box>& boxes);

}  // namespace rtog::explore_detail
