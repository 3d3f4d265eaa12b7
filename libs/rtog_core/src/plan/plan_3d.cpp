// Risk-aware 3D planning (rtog/core/plan.hpp): the map's cells in a box as a 26-connected graph,
// A* on it (the search the 2D planner uses).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "plan/astar.hpp"
#include "rtog/core/log_odds.hpp"

namespace rtog {

PlanResult3D planPath3D(const OccupancyMap& map, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                        const PlanOptions& o) {
  plan_detail::validate(o);
  if (!from.allFinite() || !to.allFinite()) throw std::invalid_argument("rtog::plan: the start and goal must be finite");
  const Lattice& lat = map.lattice();
  Key kf, kt;
  if (!lat.tryKey(from, kf) || !lat.tryKey(to, kt))
    throw std::invalid_argument("rtog::plan: the start or the goal lies beyond the key range");
  const double res = map.resolution();
  const std::int64_t rc = plan_detail::radiusCells(o, res, kPlanMaxRadiusCells3D);
  const std::int64_t margin = o.margin_cells + rc;
  // Refused before the box is built (a large radius makes it large).
  if (plan_detail::blockedAt(map, kf, o.radius / res, o, false))
    throw std::invalid_argument("rtog::plan: the start is occupied or nearer than the radius to an occupied cell");
  if (plan_detail::blockedAt(map, kt, o.radius / res, o, false))
    throw std::invalid_argument("rtog::plan: the goal is occupied or nearer than the radius to an occupied cell");
  std::array<std::int64_t, 3> lo{}, hi{}, n{};
  const Box kb = map.keyBounds();
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::min(kf[a], kt[a]), hi[a] = std::max(kf[a], kt[a]);
    if (!kb.isEmpty()) lo[a] = std::min<std::int64_t>(lo[a], kb.min[a]), hi[a] = std::max<std::int64_t>(hi[a], kb.max[a]);
    lo[a] = std::max<std::int64_t>(lo[a] - margin, kKeyMin), hi[a] = std::min<std::int64_t>(hi[a] + margin, kKeyMax);
    n[a] = hi[a] - lo[a] + 1;
  }
  constexpr std::int64_t kMaxNodes = std::int64_t{1} << 26;
  if (n[0] > kMaxNodes || n[1] > kMaxNodes || n[2] > kMaxNodes || n[0] * n[1] > kMaxNodes || n[0] * n[1] * n[2] > kMaxNodes)
    throw std::length_error("rtog::plan: the 3D planning box would have " + std::to_string(n[0] * n[1] * n[2]) +
                            " cells (more than 2^26)");
  const std::size_t total = std::size_t(n[0] * n[1] * n[2]);
  const auto index = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    return std::size_t((z * n[1] + y) * n[0] + x);
  };
  std::vector<float> risk(total, static_cast<float>(o.unknown_risk));
  std::vector<std::uint8_t> blocked(total, 0);
  const float occ = map.logOddsModel().occupiedThreshold();
  const Box region{Key{static_cast<std::int32_t>(lo[0]), static_cast<std::int32_t>(lo[1]), static_cast<std::int32_t>(lo[2])},
                   Key{static_cast<std::int32_t>(hi[0]), static_cast<std::int32_t>(hi[1]), static_cast<std::int32_t>(hi[2])}};
  map.forEachLeafIn(region, [&](const Box& b, float v) {
    const Box c = b.intersection(region);
    const auto p = static_cast<float>(probability(v));
    for (std::int64_t z = c.min.z; z <= c.max.z; ++z)
      for (std::int64_t y = c.min.y; y <= c.max.y; ++y)
        for (std::int64_t x = c.min.x; x <= c.max.x; ++x) {
          const std::size_t i = index(x - lo[0], y - lo[1], z - lo[2]);
          risk[i] = p;
          if (v >= occ) blocked[i] = 1;
        }
  });
  // The radius: a sphere about each occupied cell's centre.
  const std::int64_t extents[3] = {n[0], n[1], n[2]};
  plan_detail::blockWithinRadius(blocked, extents, o.radius / res);
  const std::size_t start = index(kf.x - lo[0], kf.y - lo[1], kf.z - lo[2]), goal = index(kt.x - lo[0], kt.y - lo[1], kt.z - lo[2]);
  if (blocked[start]) throw std::invalid_argument("rtog::plan: the start is occupied or nearer than the radius to an occupied cell");
  if (blocked[goal]) throw std::invalid_argument("rtog::plan: the goal is occupied or nearer than the radius to an occupied cell");
  const auto coords = [&](std::size_t i) {
    return std::array<std::int64_t, 3>{std::int64_t(i % std::size_t(n[0])), std::int64_t(i / std::size_t(n[0]) % std::size_t(n[1])),
                                       std::int64_t(i / std::size_t(n[0] * n[1]))};
  };
  const auto gc = coords(goal);
  const auto h = [&](std::uint32_t v) {
    const auto c = coords(v);
    return o.ta * res * std::sqrt(double((c[0] - gc[0]) * (c[0] - gc[0]) + (c[1] - gc[1]) * (c[1] - gc[1]) + (c[2] - gc[2]) * (c[2] - gc[2])));
  };
  const auto edges = [&](std::uint32_t u, const auto& relax) {
    const auto c = coords(u);
    for (int d = 0; d < 27; ++d) {
      const std::int64_t dx = d % 3 - 1, dy = d / 3 % 3 - 1, dz = d / 9 - 1;
      if (dx == 0 && dy == 0 && dz == 0) continue;
      const std::int64_t x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
      if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2]) continue;
      const std::size_t v = index(x, y, z);
      if (blocked[v]) continue;
      // No corner cut: every cell the step passes beside (a sub-step of it) is enterable.
      bool clear = true;
      for (int m = 1; m < 7 && clear; ++m) {
        const std::int64_t sx = (m & 1) ? dx : 0, sy = (m & 2) ? dy : 0, sz = (m & 4) ? dz : 0;
        if ((sx == dx && sy == dy && sz == dz) || (sx == 0 && sy == 0 && sz == 0)) continue;
        clear = !blocked[index(c[0] + sx, c[1] + sy, c[2] + sz)];
      }
      if (!clear) continue;
      const double step = res * std::sqrt(double(dx * dx + dy * dy + dz * dz));
      relax(static_cast<std::uint32_t>(v), o.ta * step + o.te * double(risk[v]));
    }
  };
  const plan_detail::Search s = plan_detail::aStar(total, static_cast<std::uint32_t>(start), static_cast<std::uint32_t>(goal), h, edges);
  PlanResult3D r;
  r.expanded = s.expanded;
  r.nodes = total;
  if (!s.found) return r;
  r.found = true;
  r.cost = s.cost;
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const auto c = coords(s.nodes[i]);
    r.path.emplace_back((lo[0] + c[0] + 0.5) * res, (lo[1] + c[1] + 0.5) * res, (lo[2] + c[2] + 0.5) * res);
    if (i > 0) {
      r.length += (r.path[i] - r.path[i - 1]).norm();
      r.risk += risk[s.nodes[i]];
    }
  }
  return r;
}

}  // namespace rtog
