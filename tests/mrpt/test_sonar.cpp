// Sonar readings (CObservationRange) as cones (doc/sonar.md), against MRPT's own grid. A ring of
// 16 sonars is simulated by COccupancyGridMap2D::sonarSimulator on real maps (Malaga campus, UWB demo)
// along random free poses (fixed seeds) and inserted into rtog's map and into a
// COccupancyGridMap2D; the classes of the cells both observed must agree, both against the truth
// map. MRPT 2.5 inserts all readings of an observation at the first one's pose with the cone
// half an aperture off (COccupancyGridMap2D_insert.cpp), so the oracle is fed one reading per
// observation with its yaw moved by half an aperture: the grid then computes the cone rtog
// means. Then localization: the likelihood of a ring's readings peaks near the true pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/random/RandomGenerators.h>

#include "grid2d_helpers.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;
using mrpt::obs::CObservationRange;
using mrpt::poses::CPose2D;
using mrpt::poses::CPose3D;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kSonars = 16;
constexpr float kAperture = static_cast<float>(20.0 * kPi / 180.0);

const MalagaFixture& uwbFixture() {
  static const MalagaFixture f = gridmapFixture("uwb_ro-localization_demo_map.gridmap.gz");
  return f;
}

CObservationRange ring() {
  CObservationRange o;
  o.sensorConeApperture = kAperture;
  o.maxSensorDistance = 4.0f;
  for (int k = 0; k < kSonars; ++k) {
    CObservationRange::TMeasurement m;
    const double a = 2.0 * kPi * k / kSonars;
    m.sensorID = static_cast<std::uint16_t>(k);
    m.sensorPose = mrpt::math::TPose3D(0.2 * std::cos(a), 0.2 * std::sin(a), 0.3, a, 0, 0);
    o.sensedData.push_back(m);
  }
  return o;
}

/// Poses in free space of the truth grid, at least `clearance` from any occupied cell and with
/// a wall within 2 m (the campus is mostly open: a sonar there echoes from nothing).
std::vector<CPose2D> freePoses(const mrpt::maps::COccupancyGridMap2D& g, std::size_t n, std::uint32_t seed,
                               double clearance) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> ux(g.getXMin(), g.getXMax()), uy(g.getYMin(), g.getYMax());
  std::uniform_real_distribution<double> yaw(-kPi, kPi);
  std::vector<CPose2D> out;
  const int c = static_cast<int>(std::ceil(clearance / g.getResolution()));
  const int near = static_cast<int>(std::ceil(2.0 / g.getResolution()));
  const auto inside = [&](int ix, int iy) {
    return ix >= 0 && iy >= 0 && ix < static_cast<int>(g.getSizeX()) && iy < static_cast<int>(g.getSizeY());
  };
  // Bounded: a map with too few such places gives fewer poses (the callers check the count).
  for (std::size_t tries = 0; out.size() < n && tries < 2000 * n; ++tries) {
    const float x = ux(rng), y = uy(rng);
    const int ix = g.x2idx(x), iy = g.y2idx(y);
    bool ok = inside(ix - near, iy - near) && inside(ix + near, iy + near);
    for (int dy = -c; ok && dy <= c; ++dy)
      for (int dx = -c; ok && dx <= c; ++dx) ok = g.getCell(ix + dx, iy + dy) > 0.6f;
    bool wall = false;
    for (int dy = -near; ok && !wall && dy <= near; dy += 2)
      for (int dx = -near; !wall && dx <= near; dx += 2) wall = g.getCell(ix + dx, iy + dy) < 0.4f;
    if (ok && wall) out.emplace_back(x, y, yaw(rng));
  }
  return out;
}

CObservationRange simulate(const mrpt::maps::COccupancyGridMap2D& truth, const CPose2D& pose) {
  CObservationRange o = ring();
  truth.sonarSimulator(o, pose, 0.5f, 0.01f, 0.0f);
  return o;
}

struct Agreement {
  std::size_t both = 0, same = 0;
  double share() const { return both ? static_cast<double>(same) / both : 0.0; }
};

/// Class agreement of two grids of P(free) over the cells both observed (P != 0.5), by cell centre.
template <class A, class B>
Agreement agreement(const A& pa, const B& pb, float x0, float x1, float y0, float y1, float res) {
  Agreement r;
  for (float y = y0 + 0.5f * res; y < y1; y += res)
    for (float x = x0 + 0.5f * res; x < x1; x += res) {
      const float a = pa(x, y), b = pb(x, y);
      if (a == 0.5f || b == 0.5f) continue;
      ++r.both;
      r.same += (a > 0.5f) == (b > 0.5f);
    }
  return r;
}

/// Rings simulated on `truth` at 400 free poses, inserted into rtog's map and the two grids; the
/// classes must agree. `keep` (RTOG_SONAR_SIMPLEMAP=FILE) saves the rings as a simplemap.
/// `beats_whole_rings`: rtog's map must also agree with the truth more often than the grid given
/// the whole rings as MRPT inserts them (held on Malaga, not on the UWB map: doc/sonar.md).
void conesAgree(const mrpt::maps::COccupancyGridMap2D& truth, const char* name, std::size_t min_cells, bool keep_rings,
                bool beats_whole_rings) {
  const float res = truth.getResolution();
  mrpt::random::getRandomGenerator().randomize(1234);
  const std::vector<CPose2D> poses = freePoses(truth, 400, 77, 0.4);
  ASSERT_EQ(poses.size(), 400u) << name;

  auto ours = mapFromIni("");  // the mrpt_grid preset, sonarConeWeighting = uniform
  ours->setGridFrame(truth.getXMin(), truth.getXMax(), truth.getYMin(), truth.getYMax());
  mrpt::maps::COccupancyGridMap2D oracle(truth.getXMin(), truth.getXMax(), truth.getYMin(), truth.getYMax(), res);
  mrpt::maps::COccupancyGridMap2D as_is(truth.getXMin(), truth.getXMax(), truth.getYMin(), truth.getYMax(), res);
  std::size_t echoes = 0;
  // RTOG_SONAR_SIMPLEMAP=FILE keeps the simulated rings as a simplemap (doc/sonar.md's pictures
  // are made from it with rtog build and MRPT's observations2map).
  mrpt::maps::CSimpleMap keep;
  for (const CPose2D& p : poses) {
    const CObservationRange o = simulate(truth, p);
    const CPose3D pose3(p);
    auto sf = mrpt::obs::CSensoryFrame::Create();
    sf->insert(std::make_shared<CObservationRange>(o));
    keep.insert(std::make_shared<mrpt::poses::CPose3DPDFGaussian>(pose3), sf);
    ASSERT_TRUE(ours->insertObservation(o, pose3));
    as_is.insertObservation(o, pose3);  // MRPT's own handling of the whole ring
    for (const auto& m : o.sensedData) {
      CObservationRange one = o;
      one.sensedData.assign(1, m);
      one.sensedData[0].sensorPose.yaw += 0.5 * o.sensorConeApperture;  // undoes the grid's offset
      oracle.insertObservation(one, pose3);
      echoes += m.sensedDistance > 0 && m.sensedDistance < o.maxSensorDistance;
    }
  }
  ASSERT_GT(echoes, 800u);
  if (const char* file = std::getenv("RTOG_SONAR_SIMPLEMAP"); file && keep_rings) {
    ASSERT_TRUE(keep.saveToFile(file)) << file;
  }
  const auto cell = [&](const auto& g) {
    return [&g](float x, float y) {
      const int ix = g.x2idx(x), iy = g.y2idx(y);
      if (ix < 0 || iy < 0 || ix >= static_cast<int>(g.getSizeX()) || iy >= static_cast<int>(g.getSizeY())) return 0.5f;
      return g.getCell(ix, iy);
    };
  };
  // COccupancyGridMap2D's cells hold P(free); rtog's map P(occupied).
  const auto ours_p = [&](float x, float y) {
    return 1.0f - static_cast<float>(ours->map().occupancy(ours->map().lattice().key(Eigen::Vector3d(x, y, 0.3))));
  };
  const float x0 = truth.getXMin(), x1 = truth.getXMax(), y0 = truth.getYMin(), y1 = truth.getYMax();
  const Agreement with_oracle = agreement(ours_p, cell(oracle), x0, x1, y0, y1, res);
  const Agreement ours_truth = agreement(ours_p, cell(truth), x0, x1, y0, y1, res);
  const Agreement oracle_truth = agreement(cell(oracle), cell(truth), x0, x1, y0, y1, res);
  const Agreement as_is_truth = agreement(cell(as_is), cell(truth), x0, x1, y0, y1, res);
  std::printf("sonar on %s (%zu poses, %zu echoes, %.2f m cells): rtog vs COccupancyGridMap2D %.4f of %zu cells; "
              "vs truth: rtog %.4f of %zu, grid %.4f of %zu, grid given whole rings %.4f of %zu\n",
              name, poses.size(), echoes, res, with_oracle.share(), with_oracle.both, ours_truth.share(), ours_truth.both,
              oracle_truth.share(), oracle_truth.both, as_is_truth.share(), as_is_truth.both);
  EXPECT_GT(with_oracle.both, min_cells) << name;
  EXPECT_GT(with_oracle.share(), 0.95) << name;
  EXPECT_GT(ours_truth.share(), oracle_truth.share() - 0.01) << name;
  if (beats_whole_rings) {
    EXPECT_GT(ours_truth.share(), as_is_truth.share()) << name;
  }
}

/// rtog's import of the map (the map a robot would localize in), readings simulated at held-out
/// poses with a wall near (at least 6 echoes), each scored over a grid of poses about the true
/// one: the best must be within 0.1 m and 5 deg of it for most poses, and nearer than where MRPT's
/// grid puts it.
void ringLocalizes(const MalagaFixture& fx, const char* name) {
  // Both as sharp as the readings (the stock 1 m and 0.35 m suit a laser scan's many beams).
  rtog::CRTreeOccupancyGridMap map = fx.map;
  mrpt::maps::COccupancyGridMap2D grid = fx.grid;
  map.likelihoodOptions.rayTracing_stdHit = 0.05f;
  grid.likelihoodOptions.LF_stdHit = 0.05f;
  mrpt::random::getRandomGenerator().randomize(99);
  std::size_t tried = 0, found = 0;
  std::vector<double> errs, errs_grid;
  for (const CPose2D& p : freePoses(fx.grid, 3000, 4242, 0.4)) {
    const CObservationRange o = simulate(fx.grid, p);
    std::size_t echoes = 0;
    for (const auto& m : o.sensedData) echoes += m.sensedDistance > 0 && m.sensedDistance < o.maxSensorDistance;
    if (echoes < 6) continue;
    // rtog's cone-aware field, and MRPT's grid scoring the axes' end points.
    double best = -1e300, best_grid = -1e300;
    CPose2D arg, arg_grid;
    for (int i = -4; i <= 4; ++i)
      for (int j = -4; j <= 4; ++j)
        for (int k = -2; k <= 2; ++k) {
          const CPose2D q(p.x() + 0.1 * i, p.y() + 0.1 * j, p.phi() + k * 5.0 * kPi / 180.0);
          const double l = map.computeObservationLikelihood(o, CPose3D(q));
          if (l > best) best = l, arg = q;
          const double lg = grid.computeObservationLikelihood(o, CPose3D(q));
          if (lg > best_grid) best_grid = lg, arg_grid = q;
        }
    ++tried;
    const double err = std::hypot(arg.x() - p.x(), arg.y() - p.y());
    errs.push_back(err);
    errs_grid.push_back(std::hypot(arg_grid.x() - p.x(), arg_grid.y() - p.y()));
    found += err <= 0.11 && std::abs(mrpt::math::wrapToPi(arg.phi() - p.phi())) <= 5.1 * kPi / 180.0;
    if (tried == 30) break;
  }
  ASSERT_EQ(tried, 30u) << name;
  std::sort(errs.begin(), errs.end());
  std::sort(errs_grid.begin(), errs_grid.end());
  std::printf("sonar localization on %s: best of 405 poses within 0.1 m and 5 deg of the truth for %zu of %zu; "
              "position error median %.3f m, 80th percentile %.3f m (COccupancyGridMap2D: %.3f m, %.3f m)\n",
              name, found, tried, errs[15], errs[24], errs_grid[15], errs_grid[24]);
  // Malaga: measured 21 of 30, median 0 m (the grid on the axes' end points: median 0.22 m). Ties
  // along a corridor's axis are where it misses: six echoes cannot tell positions along it apart.
  EXPECT_GE(found, 18u) << name;
  EXPECT_LE(errs[15], 0.05) << name;
  EXPECT_LT(errs[15], errs_grid[15]) << name;
}

}  // namespace

// The thresholds were set on the Malaga campus map; the UWB demo's map (another building, another
// resolution) was run only after they were fixed, as data the tests were not tuned on.
TEST(Sonar, ConesAgreeWithCOccupancyGridMap2DAndTheTruthOnTheMalagaMap) {
  conesAgree(malagaFixture().grid, "Malaga", 60000, true, true);
}

TEST(Sonar, ConesAgreeWithCOccupancyGridMap2DAndTheTruthOnTheUwbDemoMap) {
  // Measured when first run: rtog vs the grid 0.9652 of 90,310 cells; vs truth rtog 0.9255, the
  // grid 0.9315, the grid given whole rings 0.9263 (so that last claim is not made here).
  conesAgree(uwbFixture().grid, "the UWB demo map", 20000, false, false);
}

TEST(Sonar, TheLikelihoodOfARingPeaksNearTheTruePose) { ringLocalizes(malagaFixture(), "Malaga"); }

TEST(Sonar, TheLikelihoodOfARingPeaksNearTheTruePoseOnTheUwbDemoMap) {
  ringLocalizes(uwbFixture(), "the UWB demo map");
}

TEST(Sonar, OptionsAndBadReadings) {
  const auto refused = [](const std::string& opts, const std::string& why) {
    try {
      mapFromIni(opts);
      ADD_FAILURE() << opts << " was accepted";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("sonarConeWeighting"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refused("sonarConeWeighting=gaussian\n", "uniform or elfes");

  // Elfes weighting (octomap preset): the axis's cells take the whole step, the rim's less.
  auto elfes = mapFromIni("sensorModelPreset=octomap\nsonarConeWeighting=elfes\n");
  auto uniform = mapFromIni("sensorModelPreset=octomap\n");
  CObservationRange o;
  o.sensorConeApperture = kAperture;
  o.maxSensorDistance = 4.0f;
  o.sensedData.resize(1);
  o.sensedData[0].sensorPose = mrpt::math::TPose3D(0.01, 0.01, 0.3, 0, 0, 0);
  o.sensedData[0].sensedDistance = 2.0f;
  ASSERT_TRUE(elfes->insertObservation(o, CPose3D()));
  ASSERT_TRUE(uniform->insertObservation(o, CPose3D()));
  EXPECT_EQ(elfes->map().cellCount(), uniform->map().cellCount());
  const auto at = [](const rtog::CRTreeOccupancyGridMap& m, double x, double y) {
    return m.map().occupancy(m.map().lattice().key(Eigen::Vector3d(x, y, 0.3)));
  };
  const double rim = 1.0 * std::tan(0.4 * kAperture);  // 80 % of the half-aperture, 1 m out
  EXPECT_DOUBLE_EQ(at(*elfes, 1.0, 0.01), at(*uniform, 1.0, 0.01));  // on the axis
  EXPECT_GT(at(*elfes, 1.0, rim), at(*uniform, 1.0, rim));             // weaker free evidence
  EXPECT_LT(at(*elfes, 1.0, rim), 0.5);
  EXPECT_GT(at(*elfes, 2.0, 0.01), 0.5);                               // the arc

  // Bad data: a counted skip; a bad sensor description: an error, nothing inserted.
  const std::size_t skipped = uniform->invalidRangesSkipped;
  CObservationRange bad = o;
  bad.sensedData[0].sensedDistance = std::nanf("");
  ASSERT_TRUE(uniform->insertObservation(bad, CPose3D()));
  EXPECT_EQ(uniform->invalidRangesSkipped, skipped + 1);
  const auto cells = uniform->map().cellCount();
  bad = o;
  bad.sensorConeApperture = std::nanf("");
  EXPECT_THROW(uniform->insertObservation(bad, CPose3D()), std::invalid_argument);
  bad = o;
  bad.maxSensorDistance = -1.0f;
  EXPECT_THROW(uniform->insertObservation(bad, CPose3D()), std::invalid_argument);
  EXPECT_EQ(uniform->map().cellCount(), cells);
  EXPECT_EQ(uniform->map().checkInvariants(), "");
}

// Issue #40: Elfes weighting in the mrpt_grid preset. A cone cell takes its kind's int8 step
// scaled by its weight, rounded to whole units: the axis the grid's whole step, the rim less, a
// cell whose step rounds to 0 nothing; a cone of zero aperture is the one beam, the grid's cells.
TEST(Sonar, ElfesWeightingInTheMrptGridPresetRoundsTheGridsSteps) {
  const auto reading = [](float aperture, float x, float y, float range) {
    CObservationRange o;
    o.sensorConeApperture = aperture;
    o.maxSensorDistance = 4.0f;
    o.sensedData.resize(1);
    o.sensedData[0].sensorPose = mrpt::math::TPose3D(x, y, 0.3, 0, 0, 0);
    o.sensedData[0].sensedDistance = range;
    return o;
  };
  const auto cellAt = [](const rtog::CRTreeOccupancyGridMap& m, double x, double y) -> std::optional<int> {
    const auto v = m.map().logOdds(m.map().lattice().key(Eigen::Vector3d(x, y, 0.3)));
    if (!v) return std::nullopt;
    return static_cast<int>(std::lround(-*v * 16.0f));
  };
  auto elfes = mapFromIni("sonarConeWeighting=elfes\n");
  auto uniform = mapFromIni("");
  for (int k = 0; k < 3; ++k) {  // three readings: the steps add up, saturating as the grid's
    ASSERT_TRUE(elfes->insertObservation(reading(kAperture, 0.01f, 0.01f, 2.0f), CPose3D()));
    ASSERT_TRUE(uniform->insertObservation(reading(kAperture, 0.01f, 0.01f, 2.0f), CPose3D()));
  }
  EXPECT_EQ(cellAt(*elfes, 1.0, 0.01), cellAt(*uniform, 1.0, 0.01));  // on the axis: whole steps
  EXPECT_EQ(cellAt(*elfes, 2.0, 0.01), cellAt(*uniform, 2.0, 0.01));  // the arc on the axis
  const double rim = 1.0 * std::tan(0.4 * kAperture);
  ASSERT_TRUE(cellAt(*elfes, 1.0, rim) && cellAt(*uniform, 1.0, rim));
  EXPECT_GT(*cellAt(*elfes, 1.0, rim), 0);                           // free, and weaker
  EXPECT_LT(*cellAt(*elfes, 1.0, rim), *cellAt(*uniform, 1.0, rim));
  EXPECT_LT(elfes->map().cellCount(), uniform->map().cellCount());  // the rim's 0 steps: untouched
  EXPECT_EQ(elfes->map().checkInvariants(), "");

  // Zero aperture: the one beam, whatever the weighting.
  auto beam_elfes = mapFromIni("sonarConeWeighting=elfes\n");
  auto beam_uniform = mapFromIni("");
  for (const float y : {0.01f, 0.4f, -0.7f}) {
    ASSERT_TRUE(beam_elfes->insertObservation(reading(0.0f, 0.01f, y, 2.5f), CPose3D()));
    ASSERT_TRUE(beam_uniform->insertObservation(reading(0.0f, 0.01f, y, 2.5f), CPose3D()));
  }
  std::vector<std::pair<rtog::Box, float>> a, b;
  beam_elfes->map().forEachLeaf([&](const rtog::Box& x, float v) { a.emplace_back(x, v); });
  beam_uniform->map().forEachLeaf([&](const rtog::Box& x, float v) { b.emplace_back(x, v); });
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b);
}

// Issue #37: every reading of a CObservationRange has its own sensor pose, but only the first
// one's (what getSensorPose returns) was checked for non-finite values up front. A NaN or
// infinite component of another reading's pose left that reading's end point NaN, and the
// observation scored as if the reading were not there. Now impossible (-1e30, finite) for every
// method, on the 2D view and on the native path, whichever reading it is.
TEST(Sonar, NonFiniteSensorPoseOfAnyReadingIsImpossible) {
  const MalagaFixture& fx = uwbFixture();
  mrpt::random::getRandomGenerator().randomize(7);
  const CPose2D p = freePoses(fx.grid, 1, 4242, 0.4).front();
  const CObservationRange o = simulate(fx.grid, p);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  int checked = 0;
  for (int method = 0; method <= 6; ++method)
    for (bool view : {true, false}) {
      rtog::CRTreeOccupancyGridMap map = fx.map;
      map.likelihoodOptions.likelihoodMethod = static_cast<rtog::CRTreeOccupancyGridMap::TLikelihoodMethod>(method);
      map.likelihoodOptions.scanLikelihoodOnGridView = view;
      const std::string what = "method " + std::to_string(method) + (view ? ", 2D view" : ", native");
      EXPECT_GT(map.computeObservationLikelihood(o, CPose3D(p)), -1e29) << what;
      for (std::size_t k : {std::size_t{0}, std::size_t{5}, std::size_t{kSonars - 1}})
        for (int c = 0; c < 6; ++c)
          for (double v : {nan, inf}) {
            CObservationRange bad = o;
            double d[6];
            for (int i = 0; i < 6; ++i) d[i] = bad.sensedData[k].sensorPose[i];
            d[c] = v;
            bad.sensedData[k].sensorPose = mrpt::math::TPose3D(d[0], d[1], d[2], d[3], d[4], d[5]);
            const double l = map.computeObservationLikelihood(bad, CPose3D(p));
            EXPECT_TRUE(std::isfinite(l)) << what << ", reading " << k << ", component " << c << " = " << v;
            EXPECT_LE(l, -1e29) << what << ", reading " << k << ", component " << c << " = " << v;
            ++checked;
          }
    }
  EXPECT_EQ(checked, 7 * 2 * 3 * 12);
}

// Issue #37: inserted, a reading with a non-finite sensor pose was refused for some components
// and presets ("the origin is not finite", naming the index among the kept readings), and
// dropped or inserted silently for others (a NaN pitch with the octomap preset, a NaN roll with
// any). Now a bad sensor description as a bad aperture is: an error naming the reading, before
// any change.
TEST(Sonar, NonFiniteSensorPoseOfAnyReadingIsRefusedOnInsertion) {
  const MalagaFixture& fx = uwbFixture();
  mrpt::random::getRandomGenerator().randomize(7);
  const CPose2D p = freePoses(fx.grid, 1, 4242, 0.4).front();
  const CObservationRange o = simulate(fx.grid, p);
  for (const std::string preset : {"", "sensorModelPreset=octomap\n"}) {
    auto map = mapFromIni(preset);
    for (int c = 0; c < 6; ++c)
      for (double v : {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::infinity()}) {
        CObservationRange bad = o;
        double d[6];
        for (int i = 0; i < 6; ++i) d[i] = bad.sensedData[5].sensorPose[i];
        d[c] = v;
        bad.sensedData[5].sensorPose = mrpt::math::TPose3D(d[0], d[1], d[2], d[3], d[4], d[5]);
        const std::string what = "preset '" + preset + "', component " + std::to_string(c) + " = " + std::to_string(v);
        try {
          map->insertObservation(bad, CPose3D(p));
          ADD_FAILURE() << what << ": inserted";
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("reading 5 has a non-finite sensor pose"), std::string::npos)
              << what << ": " << e.what();
        } catch (const std::exception& e) {
          ADD_FAILURE() << what << ": " << e.what();
        }
        EXPECT_EQ(map->map().cellCount(), 0u) << what;
      }
    ASSERT_TRUE(map->insertObservation(o, CPose3D(p)));
    EXPECT_GT(map->map().cellCount(), 0u);
  }
}
