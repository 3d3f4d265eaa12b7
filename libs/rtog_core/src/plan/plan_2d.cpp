// Risk-aware 2D planning (rtog/core/plan.hpp): the band's columns as a graph, A* on it.
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>
#include <tuple>

#include "rtog/core/band.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/plan.hpp"

namespace rtog {

namespace {

void validate(const PlanOptions& o) {
  const auto bad = [](const std::string& why) { throw std::invalid_argument("rtog::plan: " + why); };
  if (!(std::isfinite(o.te) && o.te >= 0.0) || !(std::isfinite(o.ta) && o.ta >= 0.0) || !(o.te + o.ta > 0.0))
    bad("Te and Ta must be finite, non-negative and not both 0");
  if (!(o.unknown_risk >= 0.0 && o.unknown_risk <= 1.0)) bad("the unknown cells' risk must lie in [0, 1]");
  if (!(std::isfinite(o.radius) && o.radius >= 0.0)) bad("the radius must be finite and non-negative");
  if (!(o.min_z <= o.max_z)) bad("need min_z <= max_z");
  if (o.margin_cells < 0 || o.margin_cells > 1000) bad("margin_cells must lie in [0, 1000]");
}

/// The node of point p, or false if p lies outside the grid.
bool nodeOf(const PlanGrid& g, const Eigen::Vector2d& p, std::int32_t& x, std::int32_t& y) {
  if (!p.allFinite()) return false;
  const double fx = std::floor(p.x() / g.resolution) - g.x0, fy = std::floor(p.y() / g.resolution) - g.y0;
  if (!(fx >= 0 && fy >= 0 && fx < g.nx && fy < g.ny)) return false;
  x = static_cast<std::int32_t>(fx), y = static_cast<std::int32_t>(fy);
  return true;
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
  const auto rc = static_cast<std::int64_t>(std::ceil(o.radius / res));
  const std::int64_t margin = o.margin_cells + rc;
  std::int64_t x0 = std::min(kf.x, kt.x), y0 = std::min(kf.y, kt.y), x1 = std::max(kf.x, kt.x), y1 = std::max(kf.y, kt.y);
  if (!kb.isEmpty()) x0 = std::min<std::int64_t>(x0, kb.min.x), y0 = std::min<std::int64_t>(y0, kb.min.y),
                     x1 = std::max<std::int64_t>(x1, kb.max.x), y1 = std::max<std::int64_t>(y1, kb.max.y);
  x0 = std::max<std::int64_t>(x0 - margin, kKeyMin), y0 = std::max<std::int64_t>(y0 - margin, kKeyMin);
  x1 = std::min<std::int64_t>(x1 + margin, kKeyMax), y1 = std::min<std::int64_t>(y1 + margin, kKeyMax);
  const std::int64_t nx = x1 - x0 + 1, ny = y1 - y0 + 1;
  if (nx * ny > (std::int64_t{1} << 26))
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
  std::vector<std::size_t> occupied;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(best[i])) continue;
    g.known[i] = 1;
    g.risk[i] = static_cast<float>(probability(best[i]));
    if (best[i] >= occ) g.blocked[i] = 1, occupied.push_back(i);
  }
  // Cells whose centre is nearer than the radius to an occupied cell's centre.
  const double r2 = (o.radius / res) * (o.radius / res);
  for (const std::size_t i : occupied) {
    const auto cx = static_cast<std::int64_t>(i % std::size_t(nx)), cy = static_cast<std::int64_t>(i / std::size_t(nx));
    for (std::int64_t dy = -rc; dy <= rc; ++dy)
      for (std::int64_t dx = -rc; dx <= rc; ++dx) {
        const std::int64_t x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= nx || y >= ny || double(dx * dx + dy * dy) >= r2) continue;
        g.blocked[g.index(static_cast<std::int32_t>(x), static_cast<std::int32_t>(y))] = 1;
      }
  }
  return g;
}

PlanResult planOnGrid(const PlanGrid& g, const Eigen::Vector2d& from, const Eigen::Vector2d& to, const PlanOptions& o) {
  validate(o);
  std::int32_t sx, sy, tx, ty;
  if (!nodeOf(g, from, sx, sy) || !nodeOf(g, to, tx, ty))
    throw std::invalid_argument("rtog::plan: the start or the goal lies outside the planning grid");
  if (g.blocked[g.index(sx, sy)]) throw std::invalid_argument("rtog::plan: the start is occupied or nearer than the radius to an occupied cell");
  if (g.blocked[g.index(tx, ty)]) throw std::invalid_argument("rtog::plan: the goal is occupied or nearer than the radius to an occupied cell");
  const std::size_t n = g.risk.size(), goal = g.index(tx, ty);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> cost(n, kInf);
  std::vector<std::uint32_t> parent(n, std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint8_t> closed(n, 0);
  const double res = g.resolution;
  const auto h = [&](std::int32_t x, std::int32_t y) { return o.ta * res * std::hypot(double(x - tx), double(y - ty)); };
  // (f, g-cost tie-break towards deeper nodes, node): ties resolved the same way on every run.
  using Entry = std::tuple<double, double, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  const std::size_t start = g.index(sx, sy);
  cost[start] = 0.0;
  open.emplace(h(sx, sy), -0.0, static_cast<std::uint32_t>(start));
  PlanResult r;
  static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const auto [f, neg_g, u] = open.top();
    open.pop();
    (void)f;
    if (closed[u]) continue;
    closed[u] = 1;
    ++r.expanded;
    if (u == goal) break;
    const auto ux = static_cast<std::int32_t>(u % std::size_t(g.nx)), uy = static_cast<std::int32_t>(u / std::size_t(g.nx));
    for (int k = 0; k < 8; ++k) {
      const std::int32_t vx = ux + kDx[k], vy = uy + kDy[k];
      if (vx < 0 || vy < 0 || vx >= g.nx || vy >= g.ny) continue;
      const std::size_t v = g.index(vx, vy);
      if (g.blocked[v] || closed[v]) continue;
      if (k >= 4 && (g.blocked[g.index(vx, uy)] || g.blocked[g.index(ux, vy)])) continue;  // no corner cut
      const double step = k >= 4 ? res * M_SQRT2 : res;
      const double c = cost[u] + o.ta * step + o.te * double(g.risk[v]);
      if (c < cost[v]) {
        cost[v] = c;
        parent[v] = u;
        open.emplace(c + h(vx, vy), -c, static_cast<std::uint32_t>(v));
      }
    }
  }
  if (!closed[goal]) return r;
  r.found = true;
  r.cost = cost[goal];
  std::vector<std::uint32_t> nodes;
  for (std::uint32_t v = static_cast<std::uint32_t>(goal); v != start; v = parent[v]) nodes.push_back(v);
  nodes.push_back(static_cast<std::uint32_t>(start));
  std::reverse(nodes.begin(), nodes.end());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto x = static_cast<std::int32_t>(nodes[i] % std::size_t(g.nx)), y = static_cast<std::int32_t>(nodes[i] / std::size_t(g.nx));
    r.path.push_back(g.center(x, y));
    if (i > 0) {
      r.length += (r.path[i] - r.path[i - 1]).norm();
      r.risk += g.risk[nodes[i]];
    }
  }
  return r;
}

PlanResult planPath2D(const OccupancyMap& map, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                      const PlanOptions& o) {
  return planOnGrid(buildPlanGrid(map, from, to, o), from, to, o);
}

}  // namespace rtog
