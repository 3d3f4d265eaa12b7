// Risk-aware 3D planning (rtog::planPath3D) on the bundled TUM fr2 pioneer frames at 0.1 m: the path
// keeps the radius from every occupied cell (checked against the map's leaves), its cost is a
// brute-force Dijkstra's over the same cells (written here from the map's leaves, not the
// planner's grid), and as Te/Ta rises the summed risk never rises and the length never falls.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <tuple>
#include <queue>

#include "rtog/core/plan.hpp"
#include "test_support.hpp"

namespace {

const rtog::OccupancyMap& tumMap(std::vector<Eigen::Vector3d>* origins = nullptr) {
  static std::vector<Eigen::Vector3d> where;
  static const rtog::OccupancyMap m = [] {
    rtog::MapParams mp;
    mp.resolution = 0.1;
    rtog::OccupancyMap map(mp);
    rtog::InsertParams ip;
    ip.max_range = 4.0;
    const auto scans = rtog::test::loadTumScans(8);
    for (const auto& s : scans) {
      map.insertPointCloud(s.origin, s.points.data(), s.points.size(), ip);
      where.push_back(s.origin);
    }
    return map;
  }();
  if (origins) *origins = where;
  return m;
}

/// The least distance from p to an occupied cell's centre, over the map's leaves.
double clearance(const rtog::OccupancyMap& m, const Eigen::Vector3d& p) {
  static const std::vector<Eigen::Vector3d> occupied = [&] {
    std::vector<Eigen::Vector3d> c;
    const double res = m.resolution();
    m.forEachLeaf([&](const rtog::Box& b, float v) {
      if (v < m.logOddsModel().occupiedThreshold()) return;
      for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
        for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
          for (std::int32_t x = b.min.x; x <= b.max.x; ++x) c.emplace_back((x + 0.5) * res, (y + 0.5) * res, (z + 0.5) * res);
    });
    return c;
  }();
  double best = std::numeric_limits<double>::infinity();
  for (const auto& c : occupied) best = std::min(best, (c - p).norm());
  return best;
}

/// Dijkstra over the cells of the box [lo, hi] (keys), each cell's risk read by cellLogOdds.
double dijkstra(const rtog::OccupancyMap& m, const rtog::Key& lo, const rtog::Key& hi, const rtog::Key& s,
                const rtog::Key& t, const rtog::PlanOptions& o) {
  const double res = m.resolution();
  const auto inside = [&](const rtog::Key& k) {
    return k.x >= lo.x && k.y >= lo.y && k.z >= lo.z && k.x <= hi.x && k.y <= hi.y && k.z <= hi.z;
  };
  std::map<std::tuple<int, int, int>, bool> blocked_memo;
  const auto blocked = [&](const rtog::Key& k) {
    const auto key = std::make_tuple(k.x, k.y, k.z);
    if (auto it = blocked_memo.find(key); it != blocked_memo.end()) return it->second;
    const Eigen::Vector3d c((k.x + 0.5) * res, (k.y + 0.5) * res, (k.z + 0.5) * res);
    const bool b = clearance(m, c) < o.radius || m.stateAt(c) == rtog::CellState::Occupied;
    return blocked_memo[key] = b;
  };
  const auto risk = [&](const rtog::Key& k) {
    const std::optional<float> l = m.logOdds(k);
    return l ? rtog::probability(*l) : o.unknown_risk;
  };
  std::map<std::tuple<int, int, int>, double> dist;
  using E = std::pair<double, std::tuple<int, int, int>>;
  std::priority_queue<E, std::vector<E>, std::greater<E>> open;
  dist[{s.x, s.y, s.z}] = 0.0;
  open.push({0.0, {s.x, s.y, s.z}});
  while (!open.empty()) {
    const auto [d, u] = open.top();
    open.pop();
    if (d > dist[u]) continue;
    const rtog::Key ku{std::get<0>(u), std::get<1>(u), std::get<2>(u)};
    if (ku == t) return d;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy && !dz) continue;
          const rtog::Key kv{ku.x + dx, ku.y + dy, ku.z + dz};
          if (!inside(kv) || blocked(kv)) continue;
          bool ok = true;  // every sub-step's cell enterable
          for (int mask = 1; mask < 7 && ok; ++mask) {
            const rtog::Key c{ku.x + ((mask & 1) ? dx : 0), ku.y + ((mask & 2) ? dy : 0), ku.z + ((mask & 4) ? dz : 0)};
            if (c == kv || c == ku) continue;
            ok = !blocked(c);
          }
          if (!ok) continue;
          const double w = o.ta * res * std::sqrt(double(dx * dx + dy * dy + dz * dz)) + o.te * risk(kv);
          const auto v = std::make_tuple(kv.x, kv.y, kv.z);
          auto it = dist.find(v);
          if (it == dist.end() || d + w < it->second) dist[v] = d + w, open.push({d + w, v});
        }
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

TEST(Plan3D, TumPathKeepsTheRadiusAndTradesRiskForLength) {
  std::vector<Eigen::Vector3d> at;
  const rtog::OccupancyMap& m = tumMap(&at);
  ASSERT_GE(at.size(), 4u);
  rtog::PlanOptions o;
  o.radius = 0.25, o.ta = 1.0, o.unknown_risk = 0.9;
  const Eigen::Vector3d from = at.front(), to = at.back();
  double last_risk = std::numeric_limits<double>::infinity(), last_length = 0.0;
  for (const double te : {0.0, 0.3, 1.0, 3.0, 10.0}) {
    o.te = te;
    const rtog::PlanResult3D p = rtog::planPath3D(m, from, to, o);
    ASSERT_TRUE(p.found) << te;
    double clear = std::numeric_limits<double>::infinity();
    for (const auto& q : p.path) clear = std::min(clear, clearance(m, q));
    std::printf("TUM 3D, Te %.1f: %.2f m, risk %.3f, least clearance %.3f m, %zu of %zu cells expanded\n", te, p.length,
                p.risk, clear, p.expanded, p.nodes);
    EXPECT_GE(clear, o.radius - 1e-9) << te;
    for (const auto& q : p.path) EXPECT_NE(m.stateAt(q), rtog::CellState::Occupied);
    EXPECT_NEAR(p.cost, te * p.risk + p.length, 1e-9 * std::max(1.0, p.cost));
    EXPECT_LE(p.risk, last_risk + 1e-9) << te;
    EXPECT_GE(p.length, last_length - 1e-9) << te;
    last_risk = p.risk, last_length = p.length;
  }
}

TEST(Plan3D, CostIsABruteForceDijkstrasOnASmallBox) {
  std::vector<Eigen::Vector3d> at;
  const rtog::OccupancyMap& m = tumMap(&at);
  // Between the first and last camera positions (1 m apart).
  const Eigen::Vector3d from = at.front(), to = at.back();
  rtog::PlanOptions o;
  o.radius = 0.15, o.te = 2.0, o.ta = 1.0, o.unknown_risk = 0.5;
  const rtog::PlanResult3D p = rtog::planPath3D(m, from, to, o);
  ASSERT_TRUE(p.found);
  const rtog::Key s = m.lattice().key(from), t = m.lattice().key(to);
  rtog::Key lo = m.keyBounds().min, hi = m.keyBounds().max;
  for (int a = 0; a < 3; ++a) lo[a] = std::min({lo[a], s[a], t[a]}) - 3, hi[a] = std::max({hi[a], s[a], t[a]}) + 3;
  // Too big a box for the brute force: keep to the cells near the segment from s to t.
  for (int a = 0; a < 3; ++a) lo[a] = std::max(lo[a], std::min(s[a], t[a]) - 6), hi[a] = std::min(hi[a], std::max(s[a], t[a]) + 6);
  const double want = dijkstra(m, lo, hi, s, t, o);
  ASSERT_TRUE(std::isfinite(want));
  std::printf("TUM 3D hop: planner %.6f, brute force %.6f (%zu cells of the path)\n", p.cost, want, p.path.size());
  ASSERT_GT(p.path.size(), 8u);
  // The brute force is confined to cells near the segment: the planner's optimum is at most its
  // cost, and equal when the optimum stays near the segment, as here (to the planner's float T(C)).
  EXPECT_NEAR(p.cost, want, 1e-6 * std::max(1.0, want));
}

TEST(Plan3D, BadRequestsAreRefused) {
  const rtog::OccupancyMap& m = tumMap();
  rtog::PlanOptions o;
  const Eigen::Vector3d a(0, 0, 0);
  EXPECT_THROW((void)rtog::planPath3D(m, a, Eigen::Vector3d(std::nan(""), 0, 0), o), std::invalid_argument);
  EXPECT_THROW((void)rtog::planPath3D(m, a, Eigen::Vector3d(500, 500, 500), o), std::length_error);
  o.te = -1;
  EXPECT_THROW((void)rtog::planPath3D(m, a, a, o), std::invalid_argument);
}
