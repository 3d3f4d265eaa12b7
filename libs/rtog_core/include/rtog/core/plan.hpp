// Risk-aware path planning on the map (the estimator seed, section 5): the path P minimising
// f(P) = Te * sum T(C) + Ta * length(P) over the cells C it enters, T(C) the cell's probability of
// being occupied (unknown cells at a chosen risk), occupied cells and those nearer to one than the
// robot's radius never entered. 2D: the columns of a height band, as the 2D view shows them; 3D:
// the cells themselves.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

/// The largest robot radius a plan takes, in cells of the map (std::invalid_argument beyond): the
/// planning graph reaches the radius beyond the map on every side, and a larger radius alone would
/// take it past its 2^26 nodes. 2D: 4000 cells (200 m at 5 cm); 3D: 200 cells (10 m at 5 cm).
constexpr double kPlanMaxRadiusCells2D = 4000.0;
constexpr double kPlanMaxRadiusCells3D = 200.0;

struct PlanOptions {
  double te = 1.0;            ///< Te: the weight of the summed risk. (Default: 1)
  double ta = 1.0;            ///< Ta: the weight of the length, per metre. (Default: 1)
  double unknown_risk = 0.5;  ///< T(C) of an unknown cell, in [0, 1]; 1 keeps paths off them. (Default: 0.5)
  /// robot radius [m]: no path cell centre nearer to an occupied cell's. At most
  /// kPlanMaxRadiusCells2D (2D) or kPlanMaxRadiusCells3D (3D) cells of the map. (Default: 0)
  double radius = 0.0;
  double min_z = -1000.0, max_z = 1000.0;  ///< the height band [m] whose columns are planned on. (Default: all)
  /// Cells beyond the known cells' bounding box that paths may cross (unknown), besides those
  /// the radius needs. (Default: 2)
  int margin_cells = 2;
  /// 2D: a free cuboid of the map whose columns are alike (one risk, none blocked) is crossed
  /// whole, from any cell of its rim to any other, instead of cell by cell. Exact: inside such a
  /// rectangle the least cost between two cells has a closed form (diagonal steps first). Only
  /// the rims' cells are searched. (Default: true)
  bool cross_free_cuboids = true;
  /// The smallest side, in cells, of a rectangle crossed whole. (Default: 4)
  int min_cuboid_side = 4;
};

/// The graph a 2D plan searches: one node per column of the band over a rectangle of cells,
/// 8-connected, a diagonal step only between two enterable cells (no corner is cut).
struct PlanGrid {
  std::int32_t x0 = 0, y0 = 0;   ///< lattice key of node (0, 0)
  std::int32_t nx = 0, ny = 0;
  double resolution = 0.0;
  std::vector<float> risk;       ///< T(C) per node (x fastest)
  std::vector<std::uint8_t> blocked;  ///< 1: occupied, or nearer than the radius to an occupied cell
  std::vector<std::uint8_t> known;    ///< 1: the column holds a known cell in the band
  /// Rectangles of alike columns (node coordinates, inclusive) crossed whole; see
  /// PlanOptions::cross_free_cuboids.
  struct Rect {
    std::int32_t x0, y0, x1, y1;
    float risk;
  };
  std::vector<Rect> rects;
  std::vector<std::int32_t> rect_of;  ///< per node: the rectangle holding it, -1 none (empty: no rectangles)
  std::size_t index(std::int32_t x, std::int32_t y) const { return std::size_t(y) * std::size_t(nx) + std::size_t(x); }
  Eigen::Vector2d center(std::int32_t x, std::int32_t y) const {
    return Eigen::Vector2d((x0 + x + 0.5) * resolution, (y0 + y + 0.5) * resolution);
  }
};

struct PlanResult {
  bool found = false;
  std::vector<Eigen::Vector2d> path;  ///< cell centres from the start's to the goal's [m]
  double length = 0.0;                ///< [m]
  double risk = 0.0;                  ///< sum of T(C) over the cells entered (the start's not)
  double cost = 0.0;                  ///< Te * risk + Ta * length
  std::size_t expanded = 0;           ///< nodes taken from the open set
};

struct PlanResult3D {
  bool found = false;
  std::vector<Eigen::Vector3d> path;  ///< cell centres from the start's to the goal's [m]
  double length = 0.0, risk = 0.0, cost = 0.0;
  std::size_t expanded = 0;
  std::size_t nodes = 0;  ///< cells in the searched box
};

/// The planning graph of `map` for a path from `from` to `to` (it covers both). Throws
/// std::invalid_argument for bad options (a radius over kPlanMaxRadiusCells2D cells too), for a start
/// or goal occupied or nearer than the radius to an occupied cell (read from the map's leaves near
/// them, before the graph is built), std::length_error for a graph over 2^26 nodes.
PlanGrid buildPlanGrid(const OccupancyMap& map, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                       const PlanOptions& o);

/// The path of least f(P) on `grid` (A*, exact). Throws std::invalid_argument if the start or the
/// goal is blocked; found = false if no path exists.
PlanResult planOnGrid(const PlanGrid& grid, const Eigen::Vector2d& from, const Eigen::Vector2d& to, const PlanOptions& o);

/// buildPlanGrid, then planOnGrid.
PlanResult planPath2D(const OccupancyMap& map, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                      const PlanOptions& o);

/// The path of least f(P) through the map's cells in 3D: 26-connected (a diagonal step only where
/// every cell it passes beside is enterable), the radius a sphere about occupied cells' centres,
/// unknown cells at o.unknown_risk, over the known cells' bounding box (with the margin) and the
/// start and goal. o.min_z/max_z and cross_free_cuboids are not used. Throws as the 2D planner,
/// std::length_error for a box over 2^26 cells.
PlanResult3D planPath3D(const OccupancyMap& map, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                        const PlanOptions& o);

}  // namespace rtog
