// The planners' radius (plan/astar.hpp): the cells nearer than the radius to an occupied cell, by a
// distance transform rather than a disc stamped about every occupied cell (whose cost grows with
// the radius squared, or cubed in 3D, times the occupied cells).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "plan/astar.hpp"
#include "rtog/core/band.hpp"

namespace rtog::plan_detail {

std::int64_t radiusCells(const PlanOptions& o, double resolution, double max_cells) {
  const double cells = o.radius / resolution;
  if (!(cells <= max_cells)) {
    std::ostringstream m;
    m << "rtog::plan: the radius " << o.radius << " m is " << cells << " cells of " << resolution
      << " m, more than the bound of " << max_cells << " cells (" << max_cells * resolution << " m)";
    throw std::invalid_argument(m.str());
  }
  return static_cast<std::int64_t>(std::ceil(cells));
}

namespace {

/// Felzenszwalb and Huttenlocher's 1D squared distance transform of f[0..n) into d: d[p] = min over
/// q of f[q] + (p - q)^2. v, z: scratch of n and n + 1 entries.
void transform1D(const double* f, std::int64_t n, double* d, std::int64_t* v, double* z) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::int64_t k = 0;
  v[0] = 0, z[0] = -kInf, z[1] = kInf;
  for (std::int64_t q = 1; q < n; ++q) {
    const auto meet = [&](std::int64_t p) {  // where q's parabola passes below p's
      return ((f[q] + double(q * q)) - (f[p] + double(p * p))) / double(2 * (q - p));
    };
    double s = meet(v[k]);
    while (s <= z[k]) s = meet(v[--k]);  // z[0] = -inf stops it (every f is finite)
    ++k;
    v[k] = q, z[k] = s, z[k + 1] = kInf;
  }
  k = 0;
  for (std::int64_t q = 0; q < n; ++q) {
    while (z[k + 1] < double(q)) ++k;
    const double dq = double(q - v[k]);
    d[q] = dq * dq + f[v[k]];
  }
}

}  // namespace

void blockWithinRadius(std::vector<std::uint8_t>& blocked, const std::int64_t (&n)[3], double r_cells) {
  if (!(r_cells > 0.0)) return;
  const double r2 = r_cells * r_cells;
  // Squared distances at or above r2 all mean "not blocked": capped there they stay small
  // enough for a float to hold exactly (r_cells <= 4000: r2 < 2^24), and the cells below the cap
  // come out exactly as uncapped.
  const float cap = static_cast<float>(std::ceil(r2) + 1.0);
  std::vector<float> dist(blocked.size());
  for (std::size_t i = 0; i < blocked.size(); ++i) dist[i] = blocked[i] ? 0.0f : cap;
  const std::int64_t longest = std::max({n[0], n[1], n[2]});
  const auto len = static_cast<std::size_t>(longest);
  std::vector<double> f(len), d(len), z(len + 1);
  std::vector<std::int64_t> v(len);
  const std::int64_t stride[3] = {1, n[0], n[0] * n[1]};
  for (int a = 0; a < 3; ++a) {
    if (n[a] < 2) continue;
    const std::int64_t lines = std::int64_t(blocked.size()) / n[a];
    for (std::int64_t l = 0; l < lines; ++l) {
      // The l-th line along axis a: its first cell from l's coordinates on the other two axes.
      const std::int64_t below = l % stride[a], above = l / stride[a];
      const std::int64_t first = below + above * stride[a] * n[a];
      for (std::int64_t i = 0; i < n[a]; ++i) f[std::size_t(i)] = dist[std::size_t(first + i * stride[a])];
      transform1D(f.data(), n[a], d.data(), v.data(), z.data());
      for (std::int64_t i = 0; i < n[a]; ++i)
        dist[std::size_t(first + i * stride[a])] = static_cast<float>(std::min(d[std::size_t(i)], double(cap)));
    }
  }
  for (std::size_t i = 0; i < blocked.size(); ++i)
    if (double(dist[i]) < r2) blocked[i] = 1;
}

bool blockedAt(const OccupancyMap& map, const Key& c, double r_cells, const PlanOptions& o, bool band) {
  const auto reach = static_cast<std::int64_t>(std::ceil(r_cells));
  const auto clampKey = [](std::int64_t v) { return static_cast<std::int32_t>(std::clamp<std::int64_t>(v, kKeyMin, kKeyMax)); };
  Box region{Key{clampKey(c.x - reach), clampKey(c.y - reach), band ? 0 : clampKey(c.z - reach)},
             Key{clampKey(c.x + reach), clampKey(c.y + reach), band ? 0 : clampKey(c.z + reach)}};
  if (band) region = bandRegion(map, region, o.min_z, o.max_z);
  if (region.isEmpty()) return false;
  const double r2 = r_cells * r_cells;
  const float occ = map.logOddsModel().occupiedThreshold();
  bool blocked = false;
  map.forEachLeafIn(region, [&](const Box& leaf, float v) {
    if (blocked || v < occ) return;
    const Box b = leaf.intersection(region);
    double d2 = 0.0;
    for (int a = 0; a < (band ? 2 : 3); ++a) {
      const double d = double(std::clamp(c[a], b.min[a], b.max[a]) - c[a]);
      d2 += d * d;
    }
    blocked = d2 == 0.0 || d2 < r2;
  });
  return blocked;
}

}  // namespace rtog::plan_detail
