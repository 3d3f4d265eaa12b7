// Information gain and next-best views (rtog/core/explore.hpp): the gain equals a per-cell
// computation written the plain way (every cell of the map in a hash table, each ray walked, the
// cells' reach multiplied out) on small real maps; an unknown-only map gives the sensor's whole
// footprint at the prior's gain; views on the first part of SENA lie where the robot may stand,
// face unknown space, have paths and are ranked by their utility.
#include <gtest/gtest.h>

#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "rtog/core/explore.hpp"
#include "rtog/core/log_odds.hpp"
#include "rtog/core/ray_traversal.hpp"
#include "tum_map.hpp"
#include "rtog/mrpt/map_exploration.h"
#include "test_helpers.hpp"

using namespace rtog;
using namespace rtog_test;

namespace {

double bits(double p) { return p > 0 && p < 1 ? -(p * std::log2(p) + (1 - p) * std::log2(1 - p)) : 0.0; }

/// The cells a view reaches with probability over 1/2 (its footprint), walked the plain way.
std::vector<Key> footprint(const OccupancyMap& m, const Eigen::Isometry3d& pose, const ViewSensor& s);

double plainGain(const OccupancyMap& m, const Eigen::Isometry3d& pose, const ViewSensor& s,
                 std::vector<Key>* reached = nullptr) {
  std::unordered_map<Key, float, KeyHash> cells;
  m.forEachLeaf([&](const Box& b, float v) { forEachCell(b, [&](const Key& k) { cells[k] = v; }); });
  const LogOddsModel& lm = m.logOddsModel();
  std::unordered_map<Key, double, KeyHash> missed;
  const Lattice& lat = m.lattice();
  const Eigen::Vector3d o = pose.translation();
  for (const Eigen::Vector3d& r : s.rays()) {
    const Eigen::Vector3d end = o + pose.linear() * r * s.max_range;
    double reach = 1.0;
    traverseRay(lat.toLattice(o), lat.toLattice(end), lat.key(o), lat.key(end), [&](const Key& k) {
      if (reach < 1e-3) return;
      auto it = missed.find(k);
      if (it == missed.end()) it = missed.emplace(k, 1.0).first;
      it->second *= 1 - reach;
      const auto c = cells.find(k);
      if (c != cells.end() && c->second >= lm.occupiedThreshold()) reach *= 1 - probability(c->second);
    });
  }
  double total = 0;
  for (const auto& [k, q] : missed) {
    if (reached && 1 - q > 0.5) reached->push_back(k);
    const auto c = cells.find(k);
    const float l = c == cells.end() ? lm.prior() : c->second;
    const double p = probability(l);
    const double g = bits(p) - (p * bits(probability(lm.update(l, lm.hitDelta()))) +
                                (1 - p) * bits(probability(lm.update(l, lm.missDelta()))));
    total += (1 - q) * g;
  }
  return total;
}

std::vector<Key> footprint(const OccupancyMap& m, const Eigen::Isometry3d& pose, const ViewSensor& s) {
  std::vector<Key> cells;
  plainGain(m, pose, s, &cells);
  return cells;
}

/// The views of SENA's band the tests score: regions of 20 columns or more, a 0.2 m robot, a 6 m laser.
ViewOptions senaViews() {
  ViewOptions o;
  o.frontiers.planar = true;
  o.frontiers.min_z = -0.5, o.frontiers.max_z = 1.0;
  o.frontiers.min_region_cells = 20;
  o.plan.radius = 0.2;
  o.sensor.max_range = 6.0;
  return o;
}

CRTreeOccupancyGridMap::Ptr senaPart(std::size_t frames, const std::string& opts = "mergePolicy=equal") {
  auto m = mapFromIni(opts);
  for (const auto& f : loadOdometryFrames(dataset(kSena), frames))
    for (const auto& obs : *f.sf) m->insertObservation(*obs, f.pose);
  return m;
}

}  // namespace

TEST(InformationGain, EqualsThePlainPerCellSumOnRealMaps) {
  const auto m = senaPart(20);
  const OccupancyMap& map = m->map();
  ViewSensor laser;
  laser.max_range = 6.0;
  laser.beams = 91;
  ViewSensor depth;
  depth.kind = ViewSensor::Kind::Depth;
  depth.max_range = 4.0;
  depth.stride = 32;
  int checked = 0;
  for (const double x : {0.5, 2.0, 4.0})
    for (const double yaw : {0.0, 1.5, -2.5}) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.translation() = Eigen::Vector3d(x, 0.3, 0.3);
      pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      for (const ViewSensor& s : {laser, depth}) {
        const ViewGain g = informationGain(map, pose, s);
        const double want = plainGain(map, pose, s);
        EXPECT_NEAR(g.bits, want, 1e-9 * std::max(1.0, want)) << x << " " << yaw;
        EXPECT_GT(g.bits, 0.0);
        ++checked;
      }
    }
  EXPECT_EQ(checked, 18);
}

TEST(InformationGain, AnUnknownOnlyMapGivesTheWholeFootprint) {
  MapParams p;
  p.resolution = 0.1;
  OccupancyMap empty(p);
  ViewSensor laser;
  laser.max_range = 5.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.33, -0.21, 0.27);
  std::unordered_set<Key, KeyHash> footprint;
  const Lattice& lat = empty.lattice();
  for (const Eigen::Vector3d& r : laser.rays()) {
    const Eigen::Vector3d end = pose.translation() + r * laser.max_range;
    traverseRay(lat.toLattice(pose.translation()), lat.toLattice(end), lat.key(pose.translation()), lat.key(end),
                [&](const Key& k) { footprint.insert(k); });
  }
  const ViewGain g = informationGain(empty, pose, laser);
  const LogOddsModel& lm = empty.logOddsModel();
  const double p0 = probability(lm.prior());
  const double per_cell = bits(p0) - (p0 * bits(probability(lm.first(lm.hitDelta()))) +
                                      (1 - p0) * bits(probability(lm.first(lm.missDelta()))));
  EXPECT_EQ(g.cells, static_cast<std::int64_t>(footprint.size()));
  EXPECT_EQ(g.unknown_cells, g.cells);
  EXPECT_NEAR(g.bits, per_cell * double(footprint.size()), 1e-9 * g.bits);
  EXPECT_GT(footprint.size(), 3000u);
  ViewSensor bad;
  bad.max_range = -1;
  EXPECT_THROW(informationGain(empty, pose, bad), std::invalid_argument);
}

TEST(NextBestViews, OnSenaLieInFreeSpaceFaceTheUnknownAndAreRanked) {
  const auto m = senaPart(110);
  const OccupancyMap& map = m->map();
  ViewOptions o = senaViews();
  o.sensor.beams = 91;
  const auto frames = loadOdometryFrames(dataset(kSena), 110);
  const Eigen::Vector3d from(frames.back().pose.x(), frames.back().pose.y(), 0.3);
  const std::vector<View> views = nextBestViews(map, from, o);
  ASSERT_GE(views.size(), 3u);
  // Around regions the caller found: the same views.
  const std::vector<View> given = nextBestViews(map, frontierRegions(map, o.frontiers), from, o);
  ASSERT_EQ(given.size(), views.size());
  for (std::size_t i = 0; i < views.size(); ++i) EXPECT_EQ(given[i].score, views[i].score);
  EXPECT_TRUE(views.front().reachable);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const View& v = views[i];
    if (i > 0) {
      EXPECT_LE(v.score, views[i - 1].score);
    }
    EXPECT_GT(v.gain.bits, 0.0);
    EXPECT_GT(v.gain.unknown_cells, 0);
    if (v.reachable) {
      EXPECT_GE(v.path_cost, v.path_length * o.plan.ta - 1e-9);
    }
    EXPECT_FALSE(map.nearestOccupied(v.pose.translation(), 0.2).found);
  }
  // A view's gain falls once its scan is in the map: what it would learn is learnt.
  const View& best = views.front();
  const ViewGain before = best.gain;
  OccupancyMap after = map;
  std::vector<Eigen::Vector3f> ends;
  for (const Eigen::Vector3d& r : o.sensor.rays())
    ends.push_back((best.pose.translation() + best.pose.linear() * r * 3.0).cast<float>());
  after.insertPointCloud(best.pose.translation(), ends);
  EXPECT_LT(informationGain(after, best.pose, o.sensor).bits, 0.8 * before.bits);
  ViewOptions bad = o;
  bad.standoff = 0;
  EXPECT_THROW(nextBestViews(map, from, bad), std::invalid_argument);
}

// The MRPT map gives the core's regions, views (as MRPT poses) and field on its cells.
TEST(NextBestViews, TheMrptMapGivesTheCoresAnswers) {
  const auto m = senaPart(60);
  FrontierOptions band;
  band.planar = true;
  const auto a = frontierRegions(*m, band), b = frontierRegions(m->map(), band);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].cells, b[i].cells);
  ViewOptions o;
  o.frontiers = band;
  o.frontiers.min_region_cells = 20;
  const auto views = nextBestViews(*m, mrpt::math::TPoint3D(0, 0, 0.3), o);
  const auto core = nextBestViews(m->map(), Eigen::Vector3d(0, 0, 0.3), o);
  ASSERT_EQ(views.size(), core.size());
  ASSERT_FALSE(views.empty());
  for (std::size_t i = 0; i < views.size(); ++i) {
    EXPECT_EQ(views[i].view.score, core[i].score);
    const Eigen::Vector3d p = core[i].pose.translation();
    EXPECT_NEAR(views[i].pose.x(), p.x(), 1e-12);
    EXPECT_NEAR(views[i].pose.y(), p.y(), 1e-12);
    const Eigen::Vector3d fwd = core[i].pose.linear().col(0);
    EXPECT_NEAR(views[i].pose.yaw(), std::atan2(fwd.y(), fwd.x()), 1e-9);
  }
  EXPECT_EQ(occupancyAt(*m, mrpt::math::TPoint3D(1.02, 0.33, 0.31)).log_odds,
            occupancyAt(m->map(), Eigen::Vector3d(1.02, 0.33, 0.31)).log_odds);
}

// 3D: a depth camera's views on TUM frames, planned through the cells.
TEST(NextBestViews, DepthViewsIn3DOnTum) {
  MapParams p;
  p.resolution = 0.1;
  const OccupancyMap map = test::tumMap(RTOG_TEST_TUM_DIR, p, 3, 4);
  const image::DepthSequence seq = image::readTumSequence(RTOG_TEST_TUM_DIR);
  const image::WorldScan first = image::loadDepthScan(seq.frames[0], seq.intrinsics, 8);
  ViewOptions o;
  o.sensor.kind = ViewSensor::Kind::Depth;
  o.sensor.max_range = 3.0;
  o.sensor.stride = 32;
  o.frontiers.min_region_cells = 30;
  o.max_regions = 6;
  o.planned = 6;
  const std::vector<View> views = nextBestViews(map, first.origin, o);
  ASSERT_FALSE(views.empty());
  EXPECT_TRUE(views.front().reachable);
  for (const View& v : views) {
    EXPECT_EQ(map.stateAt(v.pose.translation()), CellState::Free);
    EXPECT_GT(v.gain.bits, 0.0);
  }
}

// The gain model against the log (the octomap preset: the core's own update, each cell once a
// scan): from the map of SENA's first 110 frames, each later frame's
// predicted gain (informationGain at its real sensor pose, with its laser's aperture, beams and the
// map's insertion range) against the information the frame adds when inserted alone (the sum over
// cells of 1 - H, unknown cells 0). The frames that see most must be the ones predicted to.
TEST(InformationGain, PredictsWhatSenasLaterFramesAdd) {
  const auto frames = loadOdometryFrames(dataset(kSena));
  const std::size_t first = 110;
  auto half = mapFromIni("mergePolicy=equal\nsensorModelPreset=octomap");
  for (std::size_t i = 0; i < first; ++i)
    for (const auto& obs : *frames[i].sf) half->insertObservation(*obs, frames[i].pose);
  const auto information = [](const OccupancyMap& m) {
    double total = 0;
    m.forEachLeaf([&](const Box& b, float v) { total += double(b.volume()) * (1.0 - bits(probability(v))); });
    return total;
  };
  const double before = information(half->map());
  std::vector<double> predicted, realised;
  for (std::size_t i = first; i < frames.size(); i += 3) {
    for (const auto& obs : *frames[i].sf) {
      const auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs);
      if (!scan) continue;
      const mrpt::poses::CPose3D sensor = frames[i].pose + scan->sensorPose;
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.translation() = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
      pose.linear() = Eigen::AngleAxisd(sensor.yaw(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      ViewSensor laser;
      laser.aperture = scan->aperture;
      laser.beams = static_cast<int>(scan->getScanSize());
      laser.max_range = std::min<double>(scan->maxRange, half->insertionOptions.maxDistanceInsertion);
      predicted.push_back(informationGain(half->map(), pose, laser).bits);
      auto one = mapFromIni("mergePolicy=equal\nsensorModelPreset=octomap");
      one->map() = half->map();
      one->insertObservation(*scan, frames[i].pose);
      realised.push_back(information(one->map()) - before);
    }
  }
  ASSERT_GE(predicted.size(), 30u);
  // Pearson correlation, and the ratio of the totals.
  const auto mean = [](const std::vector<double>& v) { double s = 0; for (double x : v) s += x; return s / double(v.size()); };
  const double mp = mean(predicted), mr = mean(realised);
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t k = 0; k < predicted.size(); ++k) {
    sxy += (predicted[k] - mp) * (realised[k] - mr);
    sxx += (predicted[k] - mp) * (predicted[k] - mp);
    syy += (realised[k] - mr) * (realised[k] - mr);
  }
  const double r = sxy / std::sqrt(sxx * syy);
  std::printf("%zu later frames: predicted %.1f bits a frame, realised %.1f (%.2f of it); correlation %.3f\n",
              predicted.size(), mp, mr, mr / mp, r);
  EXPECT_GT(r, 0.7);
  EXPECT_GT(mr, 0.5 * mp);
}

// The best views of the first part of SENA against the whole log: the information the whole log
// adds over each view's footprint (the cells it reaches with probability over 1/2; the sum of
// 1 - H, unknown cells 0) against the view's predicted gain. The log does not drive to the views,
// but its later frames see the regions they face.
TEST(NextBestViews, TheWholeLogRealisesTheBestViewsGain) {
  const auto frames = loadOdometryFrames(dataset(kSena));
  const std::string ini = "mergePolicy=equal\nsensorModelPreset=octomap";
  auto half = mapFromIni(ini), all = mapFromIni(ini);
  for (std::size_t i = 0; i < frames.size(); ++i)
    for (const auto& obs : *frames[i].sf) {
      if (i < 110) half->insertObservation(*obs, frames[i].pose);
      all->insertObservation(*obs, frames[i].pose);
    }
  const ViewOptions o = senaViews();
  const Eigen::Vector3d from(frames[109].pose.x(), frames[109].pose.y(), 0.3);
  const std::vector<View> views = nextBestViews(half->map(), from, o);
  ASSERT_GE(views.size(), 5u);
  const auto info = [](const OccupancyMap& m, const Key& k) {
    const auto v = m.logOdds(k);
    return v ? 1.0 - bits(probability(*v)) : 0.0;
  };
  int realised = 0;
  for (std::size_t k = 0; k < 5; ++k) {
    double added = 0;
    for (const Key& c : footprint(half->map(), views[k].pose, o.sensor)) added += info(all->map(), c) - info(half->map(), c);
    std::printf("view %zu at (%.1f, %.1f): predicted %.1f bits; the whole log adds %.1f bits over its footprint\n", k + 1,
                views[k].pose.translation().x(), views[k].pose.translation().y(), views[k].gain.bits, added);
    realised += added >= 0.5 * views[k].gain.bits;
  }
  EXPECT_GE(realised, 3);
}
