// The loop rtog-simlog drives: found on the grid's cells, without randomness, so that one map
// always gives the same log.
//
// 1. Clearance: the distance of each free cell to the nearest cell that is not (two-pass chamfer,
//    the grid's border counting as a wall). The robot may stand where it is >= the clearance.
// 2. The largest 4-connected region of such cells.
// 3. The largest obstacle that region encloses (an 8-connected set of cells outside the region,
//    not touching the grid's border).
// 4. The loop around it: a half-line is cut from the obstacle's rightmost cell to the grid's
//    right edge; the cheapest path from just below the cut to just above it, not crossing it,
//    goes once around the obstacle. A step costs its length times (1 + 2 clearance / distance to
//    the nearest wall), which keeps the path near the middle of corridors.
// 5. Corners rounded by a moving average, as long as the result keeps half the clearance.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <ostream>
#include <queue>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include "simlog.hpp"

namespace rtog::simlog {
namespace {

using mrpt::math::TPoint2D;

struct Cells {
  int sx = 0, sy = 0;
  std::size_t at(int x, int y) const { return std::size_t(y) * std::size_t(sx) + std::size_t(x); }
};

// Distance [cells] of every cell to the nearest solid cell or the border (0 on solid cells).
std::vector<float> clearance(const mrpt::maps::COccupancyGridMap2D& world, const Cells& g) {
  constexpr float kInf = std::numeric_limits<float>::max() / 4;
  const float d1 = 1.0f, d2 = std::sqrt(2.0f);
  std::vector<float> d(std::size_t(g.sx) * std::size_t(g.sy));
  for (int y = 0; y < g.sy; ++y)
    for (int x = 0; x < g.sx; ++x) {
      const float border = float(std::min(std::min(x, g.sx - 1 - x), std::min(y, g.sy - 1 - y)) + 1);
      d[g.at(x, y)] = world.getCell(x, y) > 0.5f ? std::min(kInf, border) : 0.0f;
    }
  auto relax = [&](int x, int y, int dx, int dy, float w) {
    const int nx = x + dx, ny = y + dy;
    if (nx < 0 || ny < 0 || nx >= g.sx || ny >= g.sy) return;
    float& c = d[g.at(x, y)];
    c = std::min(c, d[g.at(nx, ny)] + w);
  };
  for (int y = 0; y < g.sy; ++y)
    for (int x = 0; x < g.sx; ++x) {
      relax(x, y, -1, 0, d1), relax(x, y, 0, -1, d1), relax(x, y, -1, -1, d2), relax(x, y, 1, -1, d2);
    }
  for (int y = g.sy - 1; y >= 0; --y)
    for (int x = g.sx - 1; x >= 0; --x) {
      relax(x, y, 1, 0, d1), relax(x, y, 0, 1, d1), relax(x, y, 1, 1, d2), relax(x, y, -1, 1, d2);
    }
  return d;
}

// Labels the connected sets of cells where `in` holds (4- or 8-connected), in scan order.
std::vector<int> label(const Cells& g, const std::function<bool(std::size_t)>& in, bool eight, std::vector<std::size_t>& sizes) {
  std::vector<int> lab(std::size_t(g.sx) * std::size_t(g.sy), -1);
  std::vector<std::size_t> stack;
  for (int y0 = 0; y0 < g.sy; ++y0)
    for (int x0 = 0; x0 < g.sx; ++x0) {
      if (lab[g.at(x0, y0)] >= 0 || !in(g.at(x0, y0))) continue;
      const int id = int(sizes.size());
      sizes.push_back(0);
      lab[g.at(x0, y0)] = id;
      stack.assign(1, g.at(x0, y0));
      while (!stack.empty()) {
        const std::size_t c = stack.back();
        stack.pop_back();
        ++sizes[std::size_t(id)];
        const int x = int(c % std::size_t(g.sx)), y = int(c / std::size_t(g.sx));
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if ((dx == 0 && dy == 0) || (!eight && dx != 0 && dy != 0)) continue;
            const int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= g.sx || ny >= g.sy) continue;
            const std::size_t n = g.at(nx, ny);
            if (lab[n] < 0 && in(n)) lab[n] = id, stack.push_back(n);
          }
      }
    }
  return lab;
}

// The closed polyline resampled every `h` metres along its length (the closing segment included).
std::vector<TPoint2D> resample(const std::vector<TPoint2D>& p, double h) {
  std::vector<TPoint2D> out;
  double next = 0.0, done = 0.0;  // arc length of the next sample; of the current segment's start
  for (std::size_t i = 0; i < p.size(); ++i) {
    const TPoint2D a = p[i], b = p[(i + 1) % p.size()];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    for (; next < done + len; next += h) {
      const double t = (next - done) / len;
      out.push_back({a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t});
    }
    done += len;
  }
  return out;
}

std::string metres(double v) {
  std::ostringstream s;
  s << v << " m";
  return s.str();
}

}  // namespace

std::vector<TPoint2D> planLoop(const mrpt::maps::COccupancyGridMap2D& world, const LoopOptions& opts, std::ostream& log) {
  const Cells g{int(world.getSizeX()), int(world.getSizeY())};
  const double res = world.getResolution();
  const std::vector<float> dist = clearance(world, g);
  const float need = float(opts.clearance / res);
  auto fits = [&](std::size_t c) { return dist[c] >= need; };

  std::vector<std::size_t> region_sizes;
  const std::vector<int> region = label(g, fits, false, region_sizes);
  if (region_sizes.empty())
    throw std::runtime_error("no free space with " + metres(opts.clearance) + " clearance in the map");
  const int main_region = int(std::max_element(region_sizes.begin(), region_sizes.end()) - region_sizes.begin());
  auto inside = [&](std::size_t c) { return region[c] == main_region; };

  std::vector<std::size_t> hole_sizes;
  const std::vector<int> holes = label(g, [&](std::size_t c) { return !inside(c); }, true, hole_sizes);
  std::vector<bool> touches_border(hole_sizes.size(), false);
  for (int x = 0; x < g.sx; ++x) {
    for (int y : {0, g.sy - 1})
      if (holes[g.at(x, y)] >= 0) touches_border[std::size_t(holes[g.at(x, y)])] = true;
  }
  for (int y = 0; y < g.sy; ++y)
    for (int x : {0, g.sx - 1})
      if (holes[g.at(x, y)] >= 0) touches_border[std::size_t(holes[g.at(x, y)])] = true;
  int hole = -1;
  for (std::size_t h = 0; h < hole_sizes.size(); ++h)
    if (!touches_border[h] && (hole < 0 || hole_sizes[h] > hole_sizes[std::size_t(hole)])) hole = int(h);
  if (hole < 0)
    throw std::runtime_error("no closed loop in the map: its largest free region (" + metres(opts.clearance) +
                             " clearance) encloses no obstacle");

  // The obstacle's rightmost cell (the lowest such row): the cut runs right from it, between rows
  // y0 and y0 + 1.
  int xh = -1, y0 = -1;
  for (int y = 0; y < g.sy; ++y)
    for (int x = 0; x < g.sx; ++x)
      if (holes[g.at(x, y)] == hole && x > xh) xh = x, y0 = y;
  int xs = xh + 1;
  while (xs < g.sx && !(inside(g.at(xs, y0)) && inside(g.at(xs, y0 + 1)))) ++xs;
  if (xs >= g.sx) throw std::runtime_error("no closed loop in the map: no way past the right of the enclosed obstacle");
  auto crosses_cut = [&](int xa, int ya, int xb, int yb) {
    return std::min(ya, yb) == y0 && std::max(ya, yb) == y0 + 1 && std::min(xa, xb) >= xh;
  };

  // Dijkstra from below the cut (xs, y0) to above it (xs, y0 + 1).
  const std::size_t from = g.at(xs, y0), to = g.at(xs, y0 + 1);
  std::vector<double> cost(dist.size(), std::numeric_limits<double>::infinity());
  std::vector<std::size_t> prev(dist.size(), std::numeric_limits<std::size_t>::max());
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  cost[from] = 0.0;
  open.push({0.0, from});
  while (!open.empty()) {
    const auto [c, at] = open.top();
    open.pop();
    if (c > cost[at]) continue;
    if (at == to) break;
    const int x = int(at % std::size_t(g.sx)), y = int(at / std::size_t(g.sx));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= g.sx || ny >= g.sy) continue;
        const std::size_t n = g.at(nx, ny);
        // No corner cutting: a diagonal step needs both cells beside it, so the loop stays
        // within the region's cells and goes around the obstacle as a whole.
        if (!inside(n) || (dx != 0 && dy != 0 && !(inside(g.at(nx, y)) && inside(g.at(x, ny))))) continue;
        if (crosses_cut(x, y, nx, ny)) continue;
        const double step = (dx != 0 && dy != 0 ? std::sqrt(2.0) : 1.0) * (1.0 + 2.0 * need / dist[n]);
        if (c + step < cost[n]) cost[n] = c + step, prev[n] = at, open.push({c + step, n});
      }
  }
  if (!std::isfinite(cost[to])) throw std::runtime_error("no closed loop in the map: the obstacle cannot be driven around");
  std::vector<TPoint2D> cells;
  for (std::size_t at = to; at != from; at = prev[at])
    cells.push_back({world.idx2x(unsigned(at % std::size_t(g.sx))), world.idx2y(unsigned(at / std::size_t(g.sx)))});
  cells.push_back({world.idx2x(unsigned(xs)), world.idx2y(unsigned(y0))});
  std::reverse(cells.begin(), cells.end());

  // Round the corners; less if rounding would bring the robot closer than half the clearance.
  const double h = 0.25;
  const std::vector<TPoint2D> raw = resample(cells, h);
  auto clear_at = [&](const TPoint2D& p) {
    const int cx = world.x2idx(p.x), cy = world.y2idx(p.y);
    if (cx < 0 || cy < 0 || cx >= g.sx || cy >= g.sy) return 0.0;
    return double(dist[g.at(cx, cy)]) * res;
  };
  for (double smoothing = opts.smoothing; smoothing >= h; smoothing /= 2) {
    std::vector<TPoint2D> p = raw;
    const long w = long(smoothing / h), n = long(p.size());
    for (int pass = 0; pass < 3; ++pass) {
      std::vector<TPoint2D> q(p.size());
      for (long i = 0; i < n; ++i) {
        TPoint2D sum{0, 0};
        for (long k = -w; k <= w; ++k) sum += p[std::size_t(((i + k) % n + n) % n)];
        q[std::size_t(i)] = {sum.x / double(2 * w + 1), sum.y / double(2 * w + 1)};
      }
      p.swap(q);
    }
    if (std::all_of(p.begin(), p.end(), [&](const TPoint2D& pt) { return clear_at(pt) >= 0.5 * opts.clearance; })) {
      log << "loop: around an obstacle of " << hole_sizes[std::size_t(hole)] << " cells, in a free region of "
          << region_sizes[std::size_t(main_region)] << " cells; corners rounded over " << smoothing << " m\n";
      return p;
    }
  }
  log << "loop: around an obstacle of " << hole_sizes[std::size_t(hole)] << " cells; corners not rounded\n";
  return raw;
}

}  // namespace rtog::simlog
