// Risk-aware planning (rtog/core/plan.hpp) on real maps: SENA's loop and Malaga's CS building,
// built through the MRPT map. Paths keep the robot's radius from every occupied cell (checked
// against the map's cells, not the planner's grid); as Te/Ta rises the optimal path's summed risk
// never rises and its length never falls; on small maps A*'s cost is a brute-force Dijkstra's.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <deque>
#include <cstdio>
#include <limits>
#include <queue>
#include <random>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/nav/planners/PlannerSimple2D.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/core/plan.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;

namespace {

struct RealMap {
  rtog::CRTreeOccupancyGridMap::Ptr map;
  std::vector<Eigen::Vector2d> robot;  ///< where the robot stood: free space
};

RealMap sena(std::size_t stride = 2, std::size_t max_frames = 1u << 30) {
  RealMap r{mapFromIni(""), {}};
  const auto all = loadOdometryFrames(dataset(kSena), max_frames);
  for (std::size_t i = 0; i < all.size(); i += stride) {
    for (const auto& obs : *all[i].sf) r.map->insertObservation(*obs, all[i].pose);
    r.robot.emplace_back(all[i].pose.x(), all[i].pose.y());
  }
  return r;
}

RealMap malaga() {
  RealMap r{mapFromIni(""), {}};
  mrpt::maps::CSimpleMap sm;
  mrpt::io::CFileGZInputStream f(dataset("malaga-cs-fac-building.simplemap.gz"));
  auto ar = mrpt::serialization::archiveFrom(f);
  ar >> sm;
  for (const auto& pair : sm) {
    const mrpt::poses::CPose3D p = pair.pose->getMeanVal();
    for (const auto& obs : *pair.sf) r.map->insertObservation(*obs, p);
    r.robot.emplace_back(p.x(), p.y());
  }
  return r;
}

/// The nearest occupied cell centre of the map's band to p, by brute force over the map's leaves.
double clearance(const rtog::OccupancyMap& m, const Eigen::Vector2d& p, const rtog::PlanOptions& o) {
  double best = std::numeric_limits<double>::infinity();
  const double res = m.resolution();
  const float occ = m.logOddsModel().occupiedThreshold();
  m.forEachLeaf([&](const rtog::Box& b, float v) {
    if (v < occ) return;
    if ((b.max.z + 1) * res <= o.min_z || b.min.z * res > o.max_z) return;
    for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
      for (std::int32_t x = b.min.x; x <= b.max.x; ++x)
        best = std::min(best, std::hypot((x + 0.5) * res - p.x(), (y + 0.5) * res - p.y()));
  });
  return best;
}

/// Dijkstra over the grid's graph with no heuristic and no shortcut: the least f(P).
double dijkstra(const rtog::PlanGrid& g, std::int32_t sx, std::int32_t sy, std::int32_t tx, std::int32_t ty,
                const rtog::PlanOptions& o) {
  const std::size_t n = g.risk.size();
  std::vector<double> d(n, std::numeric_limits<double>::infinity());
  using E = std::pair<double, std::size_t>;
  std::priority_queue<E, std::vector<E>, std::greater<E>> q;
  d[g.index(sx, sy)] = 0;
  q.emplace(0.0, g.index(sx, sy));
  while (!q.empty()) {
    const auto [c, u] = q.top();
    q.pop();
    if (c > d[u]) continue;
    const auto ux = static_cast<std::int32_t>(u % std::size_t(g.nx)), uy = static_cast<std::int32_t>(u / std::size_t(g.nx));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const std::int32_t vx = ux + dx, vy = uy + dy;
        if (vx < 0 || vy < 0 || vx >= g.nx || vy >= g.ny || g.blocked[g.index(vx, vy)]) continue;
        if (dx && dy && (g.blocked[g.index(vx, uy)] || g.blocked[g.index(ux, vy)])) continue;
        const double step = (dx && dy) ? g.resolution * std::sqrt(2.0) : g.resolution;
        const double nc = c + o.ta * step + o.te * g.risk[g.index(vx, vy)];
        if (nc < d[g.index(vx, vy)]) d[g.index(vx, vy)] = nc, q.emplace(nc, g.index(vx, vy));
      }
  }
  return d[g.index(tx, ty)];
}

void pathsKeepClear(const RealMap& r, const char* name) {
  rtog::PlanOptions o;
  o.radius = 0.3;
  o.te = 1.0, o.ta = 1.0;
  const Eigen::Vector2d from = r.robot.front(), to = r.robot[r.robot.size() / 2];
  const rtog::PlanResult p = rtog::planPath2D(r.map->map(), from, to, o);
  ASSERT_TRUE(p.found) << name;
  double worst = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < p.path.size(); i += 1) worst = std::min(worst, clearance(r.map->map(), p.path[i], o));
  std::printf("%s: path of %.2f m, risk %.3f, %zu cells, %zu expanded; least clearance %.3f m\n", name, p.length, p.risk,
              p.path.size(), p.expanded, worst);
  // Not nearer than the radius: a shortest path runs along its edge (the planner compares squared
  // whole cells, exactly; the metres here round).
  EXPECT_GE(worst, o.radius - 1e-9) << name;
  EXPECT_GT(p.length, (to - from).norm() - 0.1);
}

void tradeOffIsMonotone(const RealMap& r, const char* name) {
  const Eigen::Vector2d from = r.robot.front(), to = r.robot[r.robot.size() / 2];
  rtog::PlanOptions o;
  o.radius = 0.2;
  o.ta = 1.0;
  const rtog::PlanGrid g = rtog::buildPlanGrid(r.map->map(), from, to, o);
  double last_risk = std::numeric_limits<double>::infinity(), last_length = 0;
  std::vector<std::pair<double, double>> seen;
  for (const double te : {0.0, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0}) {
    o.te = te;
    const rtog::PlanResult p = rtog::planOnGrid(g, from, to, o);
    ASSERT_TRUE(p.found);
    std::printf("%s Te/Ta %6.1f: risk %8.4f, length %7.3f m\n", name, te, p.risk, p.length);
    EXPECT_LE(p.risk, last_risk + 1e-9) << name << " Te " << te;
    EXPECT_GE(p.length, last_length - 1e-9) << name << " Te " << te;
    last_risk = p.risk, last_length = p.length;
    seen.emplace_back(p.risk, p.length);
  }
  // The trade-off is at work: the safest path is longer and less risky than the shortest.
  EXPECT_LT(seen.back().first, seen.front().first - 0.1) << name;
  EXPECT_GT(seen.back().second, seen.front().second + 0.01) << name;
}

}  // namespace

TEST(Planning, SenaPathsKeepTheRadiusFromEveryOccupiedCell) { pathsKeepClear(sena(), "SENA"); }
TEST(Planning, MalagaPathsKeepTheRadiusFromEveryOccupiedCell) { pathsKeepClear(malaga(), "Malaga"); }
TEST(Planning, SenaRiskFallsAndLengthGrowsAsTeOverTaRises) { tradeOffIsMonotone(sena(), "SENA"); }
TEST(Planning, MalagaRiskFallsAndLengthGrowsAsTeOverTaRises) { tradeOffIsMonotone(malaga(), "Malaga"); }

// Crossing the map's alike free cuboids whole (the default) against searching every cell: the same
// cost for every Te (it is exact), a path of 8-neighbour steps through unblocked cells whose summed
// cost is the reported one, and fewer nodes expanded.
void cuboidsKeepTheCost(const RealMap& r, const char* name) {
  const Eigen::Vector2d from = r.robot.front(), to = r.robot[r.robot.size() / 2];
  rtog::PlanOptions whole;
  whole.radius = 0.3, whole.ta = 1.0;
  rtog::PlanOptions cells = whole;
  cells.cross_free_cuboids = false;
  std::size_t expanded_whole = 0, expanded_cells = 0;
  for (const double te : {0.0, 1.0, 10.0}) {
    whole.te = cells.te = te;
    const rtog::PlanGrid gw = rtog::buildPlanGrid(r.map->map(), from, to, whole);
    const rtog::PlanGrid gc = rtog::buildPlanGrid(r.map->map(), from, to, cells);
    ASSERT_GT(gw.rects.size(), 100u) << name;
    ASSERT_TRUE(gc.rects.empty());
    const rtog::PlanResult a = rtog::planOnGrid(gw, from, to, whole), b = rtog::planOnGrid(gc, from, to, cells);
    ASSERT_TRUE(a.found && b.found) << name;
    EXPECT_NEAR(a.cost, b.cost, 1e-9 * std::max(1.0, b.cost)) << name << " Te " << te;
    EXPECT_NEAR(a.cost, te * a.risk + a.length, 1e-9 * std::max(1.0, b.cost)) << name << " Te " << te;
    for (std::size_t i = 1; i < a.path.size(); ++i) {
      const Eigen::Vector2d step = (a.path[i] - a.path[i - 1]) / gw.resolution;
      EXPECT_LE(step.cwiseAbs().maxCoeff(), 1.0 + 1e-9) << name << " step " << i;
      const auto x = static_cast<std::int32_t>(std::floor(a.path[i].x() / gw.resolution)) - gw.x0;
      const auto y = static_cast<std::int32_t>(std::floor(a.path[i].y() / gw.resolution)) - gw.y0;
      EXPECT_FALSE(gw.blocked[gw.index(x, y)]) << name << " cell " << i;
    }
    std::printf("%s, Te %.0f: cost %.4f both ways; %zu free cuboids crossed whole: %zu nodes expanded, cell by cell %zu\n",
                name, te, a.cost, gw.rects.size(), a.expanded, b.expanded);
    expanded_whole += a.expanded, expanded_cells += b.expanded;
  }
  EXPECT_LT(expanded_whole, expanded_cells) << name;
}

TEST(Planning, SenaCrossingFreeCuboidsWholeKeepsTheCost) { cuboidsKeepTheCost(sena(), "SENA"); }
TEST(Planning, MalagaCrossingFreeCuboidsWholeKeepsTheCost) { cuboidsKeepTheCost(malaga(), "Malaga"); }

// A small map (SENA's first frames): A* gives Dijkstra's cost for 40 random pairs of free cells
// (with the free cuboids crossed whole, the default: the brute force goes cell by cell).
TEST(Planning, AStarCostIsDijkstrasOnASmallMap) {
  const RealMap r = sena(1, 4);
  std::mt19937 rng(18);
  rtog::PlanOptions o;
  o.radius = 0.15, o.te = 2.0, o.ta = 1.0, o.unknown_risk = 0.8;
  const Eigen::Vector2d c = r.robot.front();
  const rtog::PlanGrid g = rtog::buildPlanGrid(r.map->map(), c, c, o);
  ASSERT_LT(g.risk.size(), 200000u);
  std::vector<std::pair<std::int32_t, std::int32_t>> free;
  for (std::int32_t y = 0; y < g.ny; ++y)
    for (std::int32_t x = 0; x < g.nx; ++x)
      if (!g.blocked[g.index(x, y)] && g.known[g.index(x, y)]) free.emplace_back(x, y);
  ASSERT_GT(free.size(), 1000u);
  std::size_t unreachable = 0;
  for (int i = 0; i < 40; ++i) {
    const auto [sx, sy] = free[rng() % free.size()];
    const auto [tx, ty] = free[rng() % free.size()];
    const rtog::PlanResult p = rtog::planOnGrid(g, g.center(sx, sy), g.center(tx, ty), o);
    const double want = dijkstra(g, sx, sy, tx, ty, o);
    if (!std::isfinite(want)) {
      EXPECT_FALSE(p.found);
      ++unreachable;
      continue;
    }
    ASSERT_TRUE(p.found);
    EXPECT_NEAR(p.cost, want, 1e-9 * std::max(1.0, want));
    EXPECT_NEAR(p.cost, o.te * p.risk + o.ta * p.length, 1e-9 * std::max(1.0, want));
    // The Dijkstra search expands every node it can reach; A* fewer.
  }
  EXPECT_LT(unreachable, 20u);
}

// Side by side with MRPT's PlannerSimple2D (a wavefront over the grid, obstacles grown by the
// robot's radius) on the same 2D grid: the stock-equivalent view of the same map. Figures are
// printed for doc/planning.md; what is asserted is that both find a way and that rtog's shortest
// path (Te = 0) is no longer than the wavefront's and keeps the radius.
TEST(Planning, SideBySideWithMrptsPlannerSimple2D) {
  for (const char* which : {"SENA", "Malaga"}) {
    const RealMap r = std::string(which) == "SENA" ? sena() : malaga();
    const Eigen::Vector2d from = r.robot.front(), to = r.robot[r.robot.size() / 2];
    mrpt::nav::PlannerSimple2D mrpt_planner;
    mrpt_planner.robotRadius = 0.3f;
    mrpt_planner.minStepInReturnedPath = 0.0f;  // every cell, to measure its length
    std::deque<mrpt::math::TPoint2D> mp;
    bool not_found = true;
    const auto view = r.map->gridView();
    const auto t0 = std::chrono::steady_clock::now();
    mrpt_planner.computePath(*view, mrpt::poses::CPose2D(from.x(), from.y(), 0), mrpt::poses::CPose2D(to.x(), to.y(), 0),
                             mp, not_found);
    const double mrpt_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_FALSE(not_found) << which;
    double mrpt_length = 0, mrpt_clear = std::numeric_limits<double>::infinity();
    rtog::PlanOptions o;
    o.radius = 0.3, o.te = 0.0, o.ta = 1.0;
    for (std::size_t i = 0; i < mp.size(); ++i) {
      if (i) mrpt_length += std::hypot(mp[i].x - mp[i - 1].x, mp[i].y - mp[i - 1].y);
      mrpt_clear = std::min(mrpt_clear, clearance(r.map->map(), Eigen::Vector2d(mp[i].x, mp[i].y), o));
    }
    for (const double te : {0.0, 10.0}) {
      o.te = te;
      const auto t1 = std::chrono::steady_clock::now();
      const rtog::PlanResult p = rtog::planPath2D(r.map->map(), from, to, o);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
      ASSERT_TRUE(p.found) << which;
      double clear = std::numeric_limits<double>::infinity();
      for (const auto& q : p.path) clear = std::min(clear, clearance(r.map->map(), q, o));
      std::printf("%s: PlannerSimple2D %.2f m, least clearance %.3f m, %.1f ms | rtog Te %.0f: %.2f m, risk %.3f, "
                  "least clearance %.3f m, %.1f ms, %zu nodes expanded\n",
                  which, mrpt_length, mrpt_clear, mrpt_ms, te, p.length, p.risk, clear, ms, p.expanded);
      EXPECT_GE(clear, o.radius - 1e-9) << which;
      if (te == 0.0) {
        EXPECT_LE(p.length, mrpt_length + 1e-6) << which;
      }
    }
  }
}

TEST(Planning, BadRequestsAreRefusedClearly) {
  const RealMap r = sena(1, 4);
  const rtog::OccupancyMap& m = r.map->map();
  const Eigen::Vector2d a = r.robot.front();
  rtog::PlanOptions o;
  const auto refused = [&](const rtog::PlanOptions& opt, const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
    try {
      (void)rtog::planPath2D(m, from, to, opt);
    } catch (const std::invalid_argument&) {
      return true;
    } catch (const std::length_error&) {
      return true;
    }
    return false;
  };
  rtog::PlanOptions bad = o;
  bad.te = -1;
  EXPECT_TRUE(refused(bad, a, a));
  bad = o, bad.te = 0, bad.ta = 0;
  EXPECT_TRUE(refused(bad, a, a));
  bad = o, bad.unknown_risk = 1.5;
  EXPECT_TRUE(refused(bad, a, a));
  bad = o, bad.radius = std::nan("");
  EXPECT_TRUE(refused(bad, a, a));
  EXPECT_TRUE(refused(o, a, Eigen::Vector2d(std::nan(""), 0)));
  EXPECT_TRUE(refused(o, a, Eigen::Vector2d(5e4, 5e4)));  // 2^26 cells would not hold the grid
  // A goal on an occupied cell.
  Eigen::Vector2d wall(0, 0);
  bool found = false;
  m.forEachLeaf([&](const rtog::Box& b, float v) {
    if (!found && v >= m.logOddsModel().occupiedThreshold())
      wall = Eigen::Vector2d((b.min.x + 0.5) * m.resolution(), (b.min.y + 0.5) * m.resolution()), found = true;
  });
  ASSERT_TRUE(found);
  EXPECT_TRUE(refused(o, a, wall));
}

// A radius of more cells than the stated bound (kPlanMaxRadiusCells2D / 3D) is refused, naming the
// radius and the bound, however large: never a radius of 0 (an overflowed cell count), never a
// failed allocation or a crash.
TEST(Planning, RadiiBeyondTheBoundAreRefusedNamingIt) {
  const RealMap r = sena(1, 4);
  const rtog::OccupancyMap& m = r.map->map();
  const Eigen::Vector2d a = r.robot.front();
  const double res = m.resolution();
  for (const double radius : {1e18, 1e12, 1e9, 1e6, (rtog::kPlanMaxRadiusCells2D + 1) * res}) {
    rtog::PlanOptions o;
    o.radius = radius;
    try {
      (void)rtog::planPath2D(m, a, a, o);
      ADD_FAILURE() << "radius " << radius << " m was taken";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("the radius"), std::string::npos) << what;
      EXPECT_NE(what.find("bound of 4000 cells"), std::string::npos) << what;
    }
  }
}

TEST(Planning, RadiiBeyondTheBoundAreRefusedNamingItIn3D) {
  const RealMap r = sena(1, 4);
  const rtog::OccupancyMap& m = r.map->map();
  const Eigen::Vector3d a(r.robot.front().x(), r.robot.front().y(), 0.1);
  for (const double radius : {1e18, 1e12, 1e9, (rtog::kPlanMaxRadiusCells3D + 1) * m.resolution()}) {
    rtog::PlanOptions o;
    o.radius = radius;
    try {
      (void)rtog::planPath3D(m, a, a, o);
      ADD_FAILURE() << "radius " << radius << " m was taken";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("the radius"), std::string::npos) << what;
      EXPECT_NE(what.find("bound of 200 cells"), std::string::npos) << what;
    }
  }
}

// The radius keeps off exactly the cells a disc stamped about every occupied cell's centre keeps
// off (the brute force here), for radii of a fraction of a cell to many cells.
TEST(Planning, TheRadiusBlocksTheCellsOfADiscAboutEveryOccupiedCell) {
  const RealMap r = sena(1, 4);
  const Eigen::Vector2d c = r.robot.front();
  rtog::PlanOptions o;
  o.margin_cells = 30;
  const rtog::PlanGrid occupied = rtog::buildPlanGrid(r.map->map(), c, c, o);
  for (const double radius : {0.02, 0.05, 0.07, 0.12, 0.3, 1.0}) {
    o.radius = radius;
    o.margin_cells = 30 - static_cast<int>(std::ceil(radius / occupied.resolution));
    const rtog::PlanGrid g = rtog::buildPlanGrid(r.map->map(), c, c, o);
    ASSERT_EQ(g.nx, occupied.nx);
    ASSERT_EQ(g.ny, occupied.ny);
    std::vector<std::uint8_t> want = occupied.blocked;
    const double rc = radius / g.resolution;
    const auto reach = static_cast<std::int32_t>(std::ceil(rc));
    for (std::int32_t y = 0; y < g.ny; ++y)
      for (std::int32_t x = 0; x < g.nx; ++x) {
        if (!occupied.blocked[occupied.index(x, y)]) continue;
        for (std::int32_t dy = -reach; dy <= reach; ++dy)
          for (std::int32_t dx = -reach; dx <= reach; ++dx)
            if (x + dx >= 0 && y + dy >= 0 && x + dx < g.nx && y + dy < g.ny && double(dx * dx + dy * dy) < rc * rc)
              want[g.index(x + dx, y + dy)] = 1;
      }
    std::size_t differ = 0, blocked = 0;
    for (std::size_t i = 0; i < want.size(); ++i) differ += want[i] != g.blocked[i], blocked += want[i];
    EXPECT_EQ(differ, 0u) << "radius " << radius << ": " << blocked << " cells blocked";
  }
}

// A start kept off by a large radius (150 m: 3,000 cells, within the bound) is refused from the
// map's leaves near it, before a grid of tens of millions of nodes is built.
TEST(Planning, ALargeRadiusRefusesABlockedStartFromTheMapsLeaves) {
  const RealMap r = sena(1, 4);
  rtog::PlanOptions o;
  ASSERT_TRUE(rtog::planPath2D(r.map->map(), r.robot.front(), r.robot.front(), o).found);  // free at radius 0
  ASSERT_TRUE(rtog::planPath3D(r.map->map(), Eigen::Vector3d(r.robot.front().x(), r.robot.front().y(), 0.1),
                               Eigen::Vector3d(r.robot.front().x(), r.robot.front().y(), 0.1), o).found);
  o.radius = 150.0;
  for (const bool three_d : {false, true}) {
    try {
      if (three_d) {
        const Eigen::Vector3d a(r.robot.front().x(), r.robot.front().y(), 0.1);
        rtog::PlanOptions o3 = o;
        o3.radius = 9.0;  // 180 cells: within the 3D bound
        (void)rtog::planPath3D(r.map->map(), a, a, o3);
      } else {
        (void)rtog::planPath2D(r.map->map(), r.robot.front(), r.robot.front(), o);
      }
      ADD_FAILURE() << (three_d ? "3D" : "2D") << ": planned";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("the start is occupied or nearer than the radius"), std::string::npos) << e.what();
    }
  }
}
