// Risk-aware 2D planning (rtog/core/plan.hpp): the band's columns as a graph, the map's alike free
// cuboids crossed whole, A* on it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "plan/astar.hpp"
#include "rtog/core/band.hpp"
#include "rtog/core/log_odds.hpp"

namespace rtog {

namespace plan_detail {

void validate(const PlanOptions& o) {
  const auto bad = [](const std::string& why) { throw std::invalid_argument("rtog::plan: " + why); };
  if (!(std::isfinite(o.te) && o.te >= 0.0) || !(std::isfinite(o.ta) && o.ta >= 0.0) || !(o.te + o.ta > 0.0))
    bad("Te and Ta must be finite, non-negative and not both 0");
  if (!(o.unknown_risk >= 0.0 && o.unknown_risk <= 1.0)) bad("the unknown cells' risk must lie in [0, 1]");
  if (!(std::isfinite(o.radius) && o.radius >= 0.0)) bad("the radius must be finite and non-negative");
  if (!(o.min_z <= o.max_z)) bad("need min_z <= max_z");
  if (o.margin_cells < 0 || o.margin_cells > 1000) bad("margin_cells must lie in [0, 1000]");
  if (o.min_cuboid_side < 3) bad("min_cuboid_side must be at least 3 (a rectangle with cells inside its rim)");
}

}  // namespace plan_detail

namespace {

using plan_detail::validate;

constexpr const char* kStartBlocked = "rtog::plan: the start is occupied or nearer than the radius to an occupied cell";
constexpr const char* kGoalBlocked = "rtog::plan: the goal is occupied or nearer than the radius to an occupied cell";

/// The node of point p, or false if p lies outside the grid.
bool nodeOf(const PlanGrid& g, const Eigen::Vector2d& p, std::int32_t& x, std::int32_t& y) {
  if (!p.allFinite()) return false;
  const double fx = std::floor(p.x() / g.resolution) - g.x0, fy = std::floor(p.y() / g.resolution) - g.y0;
  if (!(fx >= 0 && fy >= 0 && fx < g.nx && fy < g.ny)) return false;
  x = static_cast<std::int32_t>(fx), y = static_cast<std::int32_t>(fy);
  return true;
}

/// Whether every node of r is known, not blocked and of one risk (r's).
bool alike(const PlanGrid& g, PlanGrid::Rect& r) {
  r.risk = g.risk[g.index(r.x0, r.y0)];
  for (std::int32_t y = r.y0; y <= r.y1; ++y)
    for (std::int32_t x = r.x0; x <= r.x1; ++x) {
      const std::size_t i = g.index(x, y);
      if (!g.known[i] || g.blocked[i] || g.risk[i] != r.risk || g.rect_of[i] >= 0) return false;
    }
  return true;
}

/// The rectangles crossed whole: the band's leaves' columns, largest first, where alike and not
/// overlapping a rectangle already taken.
void findRects(const OccupancyMap& map, const PlanOptions& o, PlanGrid& g) {
  std::vector<PlanGrid::Rect> cand;
  const Box columns{Key{g.x0, g.y0, 0}, Key{g.x0 + g.nx - 1, g.y0 + g.ny - 1, 0}};
  const Box region = bandRegion(map, columns, o.min_z, o.max_z);
  if (region.isEmpty()) return;
  const float occ = map.logOddsModel().occupiedThreshold();
  map.forEachLeafIn(region, [&](const Box& b, float v) {
    const Box c = b.intersection(region);
    if (v >= occ || c.extent(0) < o.min_cuboid_side || c.extent(1) < o.min_cuboid_side) return;
    cand.push_back(PlanGrid::Rect{c.min.x - g.x0, c.min.y - g.y0, c.max.x - g.x0, c.max.y - g.y0, 0.0f});
  });
  if (cand.empty()) return;
  const auto area = [](const PlanGrid::Rect& r) { return std::int64_t(r.x1 - r.x0 + 1) * (r.y1 - r.y0 + 1); };
  std::stable_sort(cand.begin(), cand.end(), [&](const auto& a, const auto& b) { return area(a) > area(b); });
  g.rect_of.assign(g.risk.size(), -1);
  for (auto r : cand) {
    if (!alike(g, r)) continue;
    const auto id = static_cast<std::int32_t>(g.rects.size());
    g.rects.push_back(r);
    for (std::int32_t y = r.y0; y <= r.y1; ++y)
      for (std::int32_t x = r.x0; x <= r.x1; ++x) g.rect_of[g.index(x, y)] = id;
  }
  if (g.rects.empty()) g.rect_of.clear();
}

bool onRim(const PlanGrid::Rect& r, std::int32_t x, std::int32_t y) {
  return x == r.x0 || x == r.x1 || y == r.y0 || y == r.y1;
}

/// The least cost from one cell of an alike rectangle to another inside it (the cells entered
/// after the first): diagonal steps first, then straight ones.
double insideCost(const PlanGrid& g, const PlanOptions& o, float risk, std::int32_t dx, std::int32_t dy) {
  const std::int32_t lo = std::min(std::abs(dx), std::abs(dy)), hi = std::max(std::abs(dx), std::abs(dy));
  return o.ta * g.resolution * (M_SQRT2 * lo + (hi - lo)) + o.te * double(risk) * hi;
}

}  // namespace

PlanGrid buildPlanGrid(const OccupancyMap& map, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                       const PlanOptions& o) {
  validate(o);
  if (!from.allFinite() || !to.allFinite()) throw std::invalid_argument("rtog::plan: the start and goal must be finite");
  const Lattice& lat = map.lattice();
  Key kf, kt;
  if (!lat.tryKey(Eigen::Vector3d(from.x(), from.y(), 0), kf) || !lat.tryKey(Eigen::Vector3d(to.x(), to.y(), 0), kt))
    throw std::invalid_argument("rtog::plan: the start or the goal lies beyond the key range");
  const double res = map.resolution();
  const Box kb = map.keyBounds();
  const std::int64_t rc = plan_detail::radiusCells(o, res, kPlanMaxRadiusCells2D);
  const std::int64_t margin = o.margin_cells + rc;
  if (plan_detail::blockedAt(map, kf, o.radius / res, o, true)) throw std::invalid_argument(kStartBlocked);
  if (plan_detail::blockedAt(map, kt, o.radius / res, o, true)) throw std::invalid_argument(kGoalBlocked);
  std::int64_t x0 = std::min(kf.x, kt.x), y0 = std::min(kf.y, kt.y), x1 = std::max(kf.x, kt.x), y1 = std::max(kf.y, kt.y);
  if (!kb.isEmpty()) x0 = std::min<std::int64_t>(x0, kb.min.x), y0 = std::min<std::int64_t>(y0, kb.min.y),
                     x1 = std::max<std::int64_t>(x1, kb.max.x), y1 = std::max<std::int64_t>(y1, kb.max.y);
  x0 = std::max<std::int64_t>(x0 - margin, kKeyMin), y0 = std::max<std::int64_t>(y0 - margin, kKeyMin);
  x1 = std::min<std::int64_t>(x1 + margin, kKeyMax), y1 = std::min<std::int64_t>(y1 + margin, kKeyMax);
  const std::int64_t nx = x1 - x0 + 1, ny = y1 - y0 + 1;
  if (nx > (std::int64_t{1} << 26) || ny > (std::int64_t{1} << 26) || nx * ny > (std::int64_t{1} << 26))
    throw std::length_error("rtog::plan: the planning grid would have " + std::to_string(nx * ny) +
                            " cells (more than 2^26): the start or goal lies too far from the map");
  PlanGrid g;
  g.x0 = static_cast<std::int32_t>(x0), g.y0 = static_cast<std::int32_t>(y0);
  g.nx = static_cast<std::int32_t>(nx), g.ny = static_cast<std::int32_t>(ny);
  g.resolution = res;
  const std::size_t n = std::size_t(nx) * std::size_t(ny);
  std::vector<float> best(n, std::numeric_limits<float>::quiet_NaN());
  // The band's highest log-odds per column, as the 2D view shows it.
  const Box columns{Key{g.x0, g.y0, 0}, Key{static_cast<std::int32_t>(x1), static_cast<std::int32_t>(y1), 0}};
  forEachBandRun(map, bandRegion(map, columns, o.min_z, o.max_z),
                 [&](std::int32_t ky, std::int32_t kx0, std::int32_t kx1, const float* run) {
                   std::copy(run, run + (kx1 - kx0 + 1), best.begin() + std::ptrdiff_t(g.index(kx0 - g.x0, ky - g.y0)));
                 });
  const float occ = map.logOddsModel().occupiedThreshold();
  g.risk.assign(n, static_cast<float>(o.unknown_risk));
  g.blocked.assign(n, 0);
  g.known.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(best[i])) continue;
    g.known[i] = 1;
    g.risk[i] = static_cast<float>(probability(best[i]));
    if (best[i] >= occ) g.blocked[i] = 1;
  }
  // Cells whose centre is nearer than the radius to an occupied cell's centre.
  const std::int64_t extents[3] = {nx, ny, 1};
  plan_detail::blockWithinRadius(g.blocked, extents, o.radius / res);
  if (o.cross_free_cuboids) findRects(map, o, g);
  return g;
}

PlanResult planOnGrid(const PlanGrid& g, const Eigen::Vector2d& from, const Eigen::Vector2d& to, const PlanOptions& o) {
  validate(o);
  std::int32_t sx, sy, tx, ty;
  if (!nodeOf(g, from, sx, sy) || !nodeOf(g, to, tx, ty))
    throw std::invalid_argument("rtog::plan: the start or the goal lies outside the planning grid");
  if (g.blocked[g.index(sx, sy)]) throw std::invalid_argument(kStartBlocked);
  if (g.blocked[g.index(tx, ty)]) throw std::invalid_argument(kGoalBlocked);
  const auto nx = std::size_t(g.nx);
  const auto start = static_cast<std::uint32_t>(g.index(sx, sy)), goal = static_cast<std::uint32_t>(g.index(tx, ty));
  const double res = g.resolution;
  const bool rects = !g.rect_of.empty();
  const auto rectOf = [&](std::size_t i) { return rects ? g.rect_of[i] : -1; };
  const std::int32_t goal_rect = rectOf(goal);
  // A cell inside a rectangle's rim is entered only by crossing the rectangle (the goal's too).
  const auto interior = [&](std::size_t i, std::int32_t x, std::int32_t y) {
    const std::int32_t k = rectOf(i);
    return k >= 0 && !onRim(g.rects[std::size_t(k)], x, y);
  };
  const auto h = [&](std::uint32_t v) {
    return o.ta * res * std::hypot(double(std::int32_t(v % nx) - tx), double(std::int32_t(v / nx) - ty));
  };
  static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  const auto edges = [&](std::uint32_t u, const auto& relax) {
    const auto ux = static_cast<std::int32_t>(u % nx), uy = static_cast<std::int32_t>(u / nx);
    const std::int32_t ku = rectOf(u);
    const bool u_inside = interior(u, ux, uy);  // only the start
    if (ku >= 0) {
      // Across the rectangle: to every cell of its rim on a side u is not on (along u's own side
      // the ordinary steps are as cheap), and to the goal inside it.
      const PlanGrid::Rect& r = g.rects[std::size_t(ku)];
      const auto to = [&](std::int32_t x, std::int32_t y) {
        relax(static_cast<std::uint32_t>(g.index(x, y)), insideCost(g, o, r.risk, x - ux, y - uy));
      };
      if (ku == goal_rect) to(tx, ty);
      for (std::int32_t x = r.x0; x <= r.x1; ++x) {
        if (u_inside || uy != r.y0) to(x, r.y0);
        if (u_inside || uy != r.y1) to(x, r.y1);
      }
      for (std::int32_t y = r.y0 + 1; y < r.y1; ++y) {
        if (u_inside || ux != r.x0) to(r.x0, y);
        if (u_inside || ux != r.x1) to(r.x1, y);
      }
      if (u_inside) return;
    }
    for (int k = 0; k < 8; ++k) {
      const std::int32_t vx = ux + kDx[k], vy = uy + kDy[k];
      if (vx < 0 || vy < 0 || vx >= g.nx || vy >= g.ny) continue;
      const std::size_t v = g.index(vx, vy);
      if (g.blocked[v] || interior(v, vx, vy)) continue;
      if (k >= 4 && (g.blocked[g.index(vx, uy)] || g.blocked[g.index(ux, vy)])) continue;  // no corner cut
      relax(static_cast<std::uint32_t>(v), o.ta * (k >= 4 ? res * M_SQRT2 : res) + o.te * double(g.risk[v]));
    }
  };
  const plan_detail::Search s = plan_detail::aStar(g.risk.size(), start, goal, h, edges);
  PlanResult r;
  r.expanded = s.expanded;
  if (!s.found) return r;
  r.found = true;
  r.cost = s.cost;
  // Cell by cell: a crossing of a rectangle becomes its diagonal steps, then its straight ones.
  std::int32_t x = sx, y = sy;
  r.path.push_back(g.center(x, y));
  for (std::size_t i = 1; i < s.nodes.size(); ++i) {
    const auto nx_ = static_cast<std::int32_t>(s.nodes[i] % nx), ny_ = static_cast<std::int32_t>(s.nodes[i] / nx);
    while (x != nx_ || y != ny_) {
      const Eigen::Vector2d prev = g.center(x, y);
      x += (nx_ > x) - (nx_ < x);
      y += (ny_ > y) - (ny_ < y);
      r.path.push_back(g.center(x, y));
      r.length += (r.path.back() - prev).norm();
      r.risk += g.risk[g.index(x, y)];
    }
  }
  return r;
}

PlanResult planPath2D(const OccupancyMap& map, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                      const PlanOptions& o) {
  return planOnGrid(buildPlanGrid(map, from, to, o), from, to, o);
}

}  // namespace rtog
