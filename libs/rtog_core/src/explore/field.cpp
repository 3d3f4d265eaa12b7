// The occupancy field O(x) (rtog/core/explore.hpp): the log-odds at the 2^d cell centres around x
// (one R-tree query for all of them), unknown cells at the prior, interpolated multilinearly.
#include <cmath>
#include <limits>

#include "rtog/core/band.hpp"
#include "rtog/core/explore.hpp"
#include "rtog/core/log_odds.hpp"

namespace rtog {
namespace {

/// The corner cells' lower key and the weights' fractions along each axis; false if x is not
/// finite or its cells lie beyond the keys.
bool corners(const OccupancyMap& map, const Eigen::Vector3d& x, int dims, Key& k0, Eigen::Vector3d& t) {
  const double res = map.resolution();
  for (int a = 0; a < dims; ++a) {
    const double u = x[a] / res - 0.5;  // cell centres at whole numbers
    if (!(u >= double(kKeyMin) && u < double(kKeyMax))) return false;
    const double f = std::floor(u);
    k0[a] = static_cast<std::int32_t>(f);
    t[a] = u - f;
  }
  return true;
}

FieldValue finish(const OccupancyMap& map, double l, const Eigen::Vector3d& du) {
  FieldValue v;
  v.log_odds = l;
  v.probability = probability(l);
  v.gradient = du / map.resolution();
  return v;
}

FieldValue prior(const OccupancyMap& map) { return finish(map, map.logOddsModel().prior(), Eigen::Vector3d::Zero()); }

}  // namespace

FieldValue occupancyAt(const OccupancyMap& map, const Eigen::Vector3d& x) {
  Key k0;
  Eigen::Vector3d t;
  if (!corners(map, x, 3, k0, t)) return prior(map);
  const double l0 = map.logOddsModel().prior();
  double c[2][2][2];  // [z][y][x]
  for (auto& p : c)
    for (auto& q : p) q[0] = q[1] = l0;
  const Box cube{k0, Key{k0.x + 1, k0.y + 1, k0.z + 1}};
  map.forEachLeafIn(cube, [&](const Box& b, float v) {
    const Box in = b.intersection(cube);
    forEachCell(in, [&](const Key& k) { c[k.z - k0.z][k.y - k0.y][k.x - k0.x] = v; });
  });
  const auto lerp = [](double a, double b, double s) { return a + (b - a) * s; };
  double l = 0;
  Eigen::Vector3d du = Eigen::Vector3d::Zero();
  // Along x for each (y, z) edge, then y, then z; each derivative from the same terms.
  double ex[2][2], dx[2][2];
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y) ex[z][y] = lerp(c[z][y][0], c[z][y][1], t.x()), dx[z][y] = c[z][y][1] - c[z][y][0];
  double ey[2], dyx[2], dyy[2];
  for (int z = 0; z < 2; ++z) {
    ey[z] = lerp(ex[z][0], ex[z][1], t.y());
    dyx[z] = lerp(dx[z][0], dx[z][1], t.y());
    dyy[z] = ex[z][1] - ex[z][0];
  }
  l = lerp(ey[0], ey[1], t.z());
  du.x() = lerp(dyx[0], dyx[1], t.z());
  du.y() = lerp(dyy[0], dyy[1], t.z());
  du.z() = ey[1] - ey[0];
  return finish(map, l, du);
}

FieldValue occupancyAt2D(const OccupancyMap& map, const Eigen::Vector3d& x, double min_z, double max_z) {
  Key k0;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  if (!(min_z <= max_z) || !corners(map, x, 2, k0, t)) return prior(map);
  const double l0 = map.logOddsModel().prior();
  double c[2][2] = {{l0, l0}, {l0, l0}};  // [y][x]
  const Box columns{Key{k0.x, k0.y, 0}, Key{k0.x + 1, k0.y + 1, 0}};
  const Box region = bandRegion(map, columns, min_z, max_z);
  if (!region.isEmpty()) {
    double best[2][2];
    bool known[2][2] = {{false, false}, {false, false}};
    map.forEachLeafIn(region, [&](const Box& b, float v) {
      const Box in = b.intersection(region);
      for (std::int32_t y = in.min.y; y <= in.max.y; ++y)
        for (std::int32_t xx = in.min.x; xx <= in.max.x; ++xx) {
          double& m = best[y - k0.y][xx - k0.x];
          bool& kn = known[y - k0.y][xx - k0.x];
          if (!kn || v > m) m = v, kn = true;  // the band's rule: the column's highest log-odds
        }
    });
    for (int y = 0; y < 2; ++y)
      for (int xx = 0; xx < 2; ++xx)
        if (known[y][xx]) c[y][xx] = best[y][xx];
  }
  const double ex0 = c[0][0] + (c[0][1] - c[0][0]) * t.x(), ex1 = c[1][0] + (c[1][1] - c[1][0]) * t.x();
  Eigen::Vector3d du;
  du.x() = (c[0][1] - c[0][0]) + ((c[1][1] - c[1][0]) - (c[0][1] - c[0][0])) * t.y();
  du.y() = ex1 - ex0;
  du.z() = 0.0;
  return finish(map, ex0 + (ex1 - ex0) * t.y(), du);
}

}  // namespace rtog
