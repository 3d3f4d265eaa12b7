// The cone rule of sonar and IR readings (rtog/core/cone.hpp, doc/sonar.md): a zero aperture is
// the beam model's one beam bit for bit; the cone's cells against a plain geometric test of
// every cell around it; the weights; the values a map takes; bad readings change nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include "rtog/core/cone.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "map_cells.hpp"

using namespace rtog;

namespace {

constexpr double kPi = 3.14159265358979323846;

MapParams params(MergePolicy merge = MergePolicy::Off) {
  MapParams p;
  p.resolution = 0.05;
  p.merge = merge;
  return p;
}

std::vector<ConeReading> randomReadings(std::uint32_t seed, std::size_t n, double aperture) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-2.0, 2.0), yaw(-kPi, kPi), range(0.02, 4.0), coin(0.0, 1.0);
  std::vector<ConeReading> out;
  for (std::size_t i = 0; i < n; ++i) {
    ConeReading r;
    r.origin = Eigen::Vector3d(pos(rng), pos(rng), 0.3);
    r.yaw = yaw(rng);
    r.aperture = aperture;
    r.range = range(rng);
    r.hit = coin(rng) < 0.8;
    out.push_back(r);
  }
  return out;
}

double angleOff(const ConeReading& r, double x, double y) {  // of a point from the axis, by acos
  const double vx = x - r.origin.x(), vy = y - r.origin.y(), d = std::hypot(vx, vy);
  if (d == 0.0) return 0.0;
  return std::acos(std::clamp((vx * std::cos(r.yaw) + vy * std::sin(r.yaw)) / d, -1.0, 1.0));
}

}  // namespace

TEST(Cone, ZeroApertureIsTheBeamModelBitForBit) {
  // Readings one at a time into both maps, some cut at max_range: the same cells, the same values.
  for (const bool planar_cache : {true, false}) {
    OccupancyMap cones(params()), beams(params());
    InsertParams ip;
    ip.max_range = 3.0;
    ip.planar_cache = planar_cache;
    for (const ConeReading& r : randomReadings(11, 300, 0.0)) {
      const InsertStats a = cones.insertCones(&r, 1, ConeWeighting::Elfes, ip);
      const Eigen::Vector3d e = r.origin + r.range * Eigen::Vector3d(std::cos(r.yaw), std::sin(r.yaw), 0.0);
      const std::vector<Eigen::Vector3f> pt{e.cast<float>()};
      const std::uint8_t hit = r.hit ? 1 : 0;
      const InsertStats b = beams.insertPointCloud(r.origin, pt.data(), 1, ip, &hit);
      ASSERT_EQ(a.rays_hit + a.rays_truncated, b.rays_hit + b.rays_truncated);
    }
    const test::CellValues a = test::cellsOf(cones), b = test::cellsOf(beams);
    ASSERT_GT(a.size(), 1000u);
    EXPECT_EQ(a, b) << "planar_cache " << planar_cache;
    EXPECT_EQ(cones.checkInvariants(), "");
  }
}

TEST(Cone, CellsAgreeWithAPlainTestOfEveryCellAround) {
  const Lattice lat(0.05);
  for (const double aperture_deg : {5.0, 25.0, 90.0, 180.0})
    for (const ConeWeighting w : {ConeWeighting::Uniform, ConeWeighting::Elfes})
      for (const ConeReading& r : randomReadings(23, 40, aperture_deg * kPi / 180.0)) {
        std::vector<ConeCell> cells;
        std::int32_t layer = 0;
        coneCells(lat, r, w, cells, &layer);
        EXPECT_EQ(layer, lat.key(r.origin).z);
        std::map<std::pair<std::int32_t, std::int32_t>, ConeCell> by;
        for (std::size_t i = 0; i < cells.size(); ++i) {
          if (i > 0) {  // ascending (y, x), each once
            const ConeCell& p = cells[i - 1];
            ASSERT_TRUE(p.y < cells[i].y || (p.y == cells[i].y && p.x < cells[i].x));
          }
          by[{cells[i].x, cells[i].y}] = cells[i];
        }
        // The axis's cells: walked here by fine steps (a superset test: each is in, and kinds).
        const Key end = lat.key(r.origin + r.range * Eigen::Vector3d(std::cos(r.yaw), std::sin(r.yaw), 0.0));
        if (r.hit) {
          const auto e = by.find(std::make_pair(end.x, end.y));
          ASSERT_NE(e, by.end());
          EXPECT_EQ(e->second.kind, StepKind::Occupied);
        }
        // Every cell around, by its centre.
        const double res = lat.resolution(), half = 0.5 * r.aperture;
        const Key o = lat.key(r.origin);
        const int reach = static_cast<int>(std::ceil(r.range / res)) + 3;
        for (int y = o.y - reach; y <= o.y + reach; ++y)
          for (int x = o.x - reach; x <= o.x + reach; ++x) {
            const double cx = (x + 0.5) * res, cy = (y + 0.5) * res;
            const double d = std::hypot(cx - r.origin.x(), cy - r.origin.y()) / res, th = angleOff(r, cx, cy);
            const double rr = r.range / res;
            const auto it = by.find({x, y});
            // Margins keep rounding at the borders out of the test.
            // Without an echo the arc is not part of the cone.
            const double far = r.hit ? rr + 0.5 : rr - 0.5;
            const bool inside = th < half - 1e-6 && d < far - 1e-6 && (w == ConeWeighting::Uniform || th < half * 0.999);
            const bool outside = th > half + 1e-6 || d > far + 1e-6;
            if (inside) {
              ASSERT_NE(it, by.end()) << "cell " << x << "," << y << " of the cone is missing: d " << d << " theta "
                                      << th << " half " << half << " range " << rr << " origin " << r.origin.x() / res
                                      << "," << r.origin.y() / res << " yaw " << r.yaw;
              const bool arc = d > rr - 0.5 + 1e-6;
              if (r.hit && arc) {
                EXPECT_EQ(it->second.kind, StepKind::Occupied);
              }
              if (d < rr - 0.5 - 1e-6 && it->second.kind != StepKind::Occupied) {
                EXPECT_EQ(it->second.kind, r.hit ? StepKind::Free : StepKind::FreeNoEcho);
                const double t = th / half;
                const double want = w == ConeWeighting::Elfes ? 1.0 - t * t : 1.0;
                EXPECT_GE(it->second.weight, static_cast<float>(want) - 1e-5f);  // the axis may raise it to 1
              }
            } else if (outside && it != by.end()) {
              // Only the axis reaches outside: its cells have weight 1 and lie within a cell of it.
              EXPECT_EQ(it->second.weight, 1.0f);
              const double ax = std::cos(r.yaw), ay = std::sin(r.yaw);
              const double off = std::abs((cx - r.origin.x()) * ay - (cy - r.origin.y()) * ax) / res;
              EXPECT_LT(off, 0.75) << "cell " << x << "," << y << " outside the cone and off the axis";
            }
          }
      }
}

TEST(Cone, CellsTakeTheirWeightOfTheStepOnce) {
  MapParams p = params();
  OccupancyMap map(p);
  ConeReading r;
  r.origin = Eigen::Vector3d(0.01, 0.02, 0.3);
  r.yaw = 0.4;
  r.aperture = 30.0 * kPi / 180.0;
  r.range = 2.0;
  InsertParams ip;
  const InsertStats s = map.insertCones(&r, 1, ConeWeighting::Elfes, ip);
  EXPECT_EQ(s.rays_hit, 1u);
  std::vector<ConeCell> cells;
  std::int32_t layer = 0;
  coneCells(map.lattice(), r, ConeWeighting::Elfes, cells, &layer);
  const LogOddsModel& m = map.logOddsModel();
  std::size_t occ = 0, fr = 0;
  for (const ConeCell& c : cells) {
    const float delta = c.weight * (c.kind == StepKind::Occupied ? m.hitDelta() : m.missDelta());
    const std::optional<float> v = map.logOdds(Key{c.x, c.y, layer});
    ASSERT_TRUE(v.has_value());
    EXPECT_FLOAT_EQ(*v, m.first(delta));
    (c.kind == StepKind::Occupied ? occ : fr) += 1;
  }
  EXPECT_EQ(static_cast<std::size_t>(map.cellCount()), cells.size());
  EXPECT_GT(occ, 10u);  // the arc: 2 m * 0.52 rad / 5 cm, about 20 cells
  EXPECT_GT(fr, 300u);  // the sector: 0.5 * 0.52 rad * (40 cells)^2, about 420
  // A second reading of the same: each cell takes its step again.
  map.insertCones(&r, 1, ConeWeighting::Elfes, ip);
  for (const ConeCell& c : cells) {
    const float delta = c.weight * (c.kind == StepKind::Occupied ? m.hitDelta() : m.missDelta());
    EXPECT_FLOAT_EQ(*map.logOdds(Key{c.x, c.y, layer}), m.update(m.first(delta), delta));
  }
}

TEST(Cone, BadReadingsThrowAndChangeNothing) {
  OccupancyMap map(params(MergePolicy::Equal));
  std::vector<ConeReading> good = randomReadings(5, 20, 0.3);
  map.insertCones(good.data(), good.size(), ConeWeighting::Uniform, {});
  const test::CellValues before = test::cellsOf(map);
  auto bad = [&](auto edit) {
    std::vector<ConeReading> rs = randomReadings(6, 5, 0.3);
    edit(rs[3]);
    EXPECT_ANY_THROW(map.insertCones(rs.data(), rs.size(), ConeWeighting::Uniform, {}));
    EXPECT_EQ(test::cellsOf(map), before);
  };
  bad([](ConeReading& r) { r.aperture = 4.0; });
  bad([](ConeReading& r) { r.aperture = -0.1; });
  bad([](ConeReading& r) { r.origin.x() = std::nan(""); });
  bad([](ConeReading& r) { r.origin.x() = 1e12; });
  // Bad data in a reading: a counted skip, and nothing changes.
  ConeReading r = good[0];
  r.range = std::nan("");
  EXPECT_EQ(map.insertCones(&r, 1, ConeWeighting::Uniform, {}).skipped_non_finite, 1u);
  r = good[0];
  r.yaw = INFINITY;
  EXPECT_EQ(map.insertCones(&r, 1, ConeWeighting::Uniform, {}).skipped_non_finite, 1u);
  r = good[0];
  r.range = -1.0;
  EXPECT_EQ(map.insertCones(&r, 1, ConeWeighting::Uniform, {}).skipped_zero_length, 1u);
  r.range = 0.0;
  EXPECT_EQ(map.insertCones(&r, 1, ConeWeighting::Uniform, {}).skipped_zero_length, 1u);
  EXPECT_EQ(test::cellsOf(map), before);
  EXPECT_EQ(map.checkInvariants(), "");
  EXPECT_THROW(coneWeightingFromString("gaussian"), std::invalid_argument);
  EXPECT_EQ(coneWeightingFromString(toString(ConeWeighting::Elfes)), ConeWeighting::Elfes);
}

TEST(Cone, ReadingsAreBeamsForRangeLimitsAndCounts) {
  OccupancyMap map(params());
  InsertParams ip;
  ip.max_range = 1.0;
  ip.max_ray_cells = 100;  // 5 m
  std::vector<ConeReading> rs(3);
  for (ConeReading& r : rs) {
    r.origin = Eigen::Vector3d(0.01, 0.01, 0.01);
    r.aperture = 0.2;
  }
  rs[0].range = 0.5;  // a hit
  rs[1].range = 2.0;  // cut at 1 m: free up to it, no arc
  ip.max_range = 1.0;
  rs[2].range = 0.7;
  rs[2].hit = false;
  const InsertStats s = map.insertCones(rs.data(), rs.size(), ConeWeighting::Elfes, ip);
  EXPECT_EQ(s.rays_hit, 1u);
  EXPECT_EQ(s.rays_truncated, 2u);
  // Nothing occupied beyond the first reading's arc.
  std::size_t occupied_far = 0;
  map.forEachLeaf([&](const Box& b, float v) {
    if (v > 0 && std::hypot(b.min.x * 0.05, b.min.y * 0.05) > 0.6) ++occupied_far;
  });
  EXPECT_EQ(occupied_far, 0u);
  ip.max_range = -1.0;
  ConeReading far = rs[0];
  far.range = 10.0;  // 200 cells > max_ray_cells
  const InsertStats t = map.insertCones(&far, 1, ConeWeighting::Elfes, ip);
  EXPECT_EQ(t.skipped_too_long, 1u);
  EXPECT_EQ(t.cells_free + t.cells_occupied, 0u);
}
