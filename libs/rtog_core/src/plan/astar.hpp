// Private to the planners: A* over nodes 0..n-1, the one search both planning grids use, and the
// options' checks.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <queue>
#include <tuple>
#include <vector>

#include "rtog/core/plan.hpp"

namespace rtog::plan_detail {

/// Throws std::invalid_argument for options no plan can use (both planners check them first).
void validate(const PlanOptions& o);

/// The radius in whole cells of `resolution` (rounded up); throws std::invalid_argument naming the
/// radius and the bound if it exceeds `max_cells` (kPlanMaxRadiusCells2D or 3D).
std::int64_t radiusCells(const PlanOptions& o, double resolution, double max_cells);

/// Blocks every cell whose centre lies nearer than `r_cells` cells to the centre of a cell blocked
/// already: the same cells as a disc (sphere) stamped about each of them, in time linear in the
/// grid whatever the radius (an exact Euclidean distance transform, squared distances capped just
/// above r_cells^2). `n`: the grid's extents, x fastest (n[2] = 1 in 2D).
void blockWithinRadius(std::vector<std::uint8_t>& blocked, const std::int64_t (&n)[3], double r_cells);

/// Whether the cell `c` is occupied or its centre nearer than `r_cells` cells to an occupied
/// cell's: 2D (`band`) over the columns of the band o.min_z..o.max_z (z of `c` unused), else over
/// the cells. Read from the map's leaves within the radius, whatever the grid would be: a start or
/// goal kept off by a large radius is refused before any grid is built.
bool blockedAt(const OccupancyMap& map, const Key& c, double r_cells, const PlanOptions& o, bool band);


struct Search {
  bool found = false;
  std::vector<std::uint32_t> nodes;  ///< start .. goal, as the edges were taken
  double cost = 0.0;
  std::size_t expanded = 0;  ///< nodes taken from the open set
};

/// Least-cost path from `start` to `goal`. `h(v)`: an admissible, consistent estimate of v's cost
/// to the goal. `edges(u, relax)`: calls relax(v, cost of the edge u -> v) for each edge out of u.
/// Ties are broken towards deeper nodes, the same way on every run.
template <class Heuristic, class Edges>
Search aStar(std::size_t n, std::uint32_t start, std::uint32_t goal, Heuristic&& h, Edges&& edges) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<double> cost(n, kInf);
  std::vector<std::uint32_t> parent(n, kNone);
  std::vector<std::uint8_t> closed(n, 0);
  using Entry = std::tuple<double, double, std::uint32_t>;  // (f, -g, node)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  cost[start] = 0.0;
  open.emplace(h(start), -0.0, start);
  Search s;
  while (!open.empty()) {
    const std::uint32_t u = std::get<2>(open.top());
    open.pop();
    if (closed[u]) continue;
    closed[u] = 1;
    ++s.expanded;
    if (u == goal) break;
    const double cu = cost[u];
    edges(u, [&](std::uint32_t v, double w) {
      if (closed[v]) return;
      const double c = cu + w;
      if (c < cost[v]) {
        cost[v] = c;
        parent[v] = u;
        open.emplace(c + h(v), -c, v);
      }
    });
  }
  if (!closed[goal]) return s;
  s.found = true;
  s.cost = cost[goal];
  for (std::uint32_t v = goal; v != start; v = parent[v]) s.nodes.push_back(v);
  s.nodes.push_back(start);
  std::reverse(s.nodes.begin(), s.nodes.end());
  return s;
}

}  // namespace rtog::plan_detail
