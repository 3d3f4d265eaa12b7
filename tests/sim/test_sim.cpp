// The synthetic world (libs/rtog_sim): ray casting against brute force, determinism, sensor
// noise statistics, exact ground truth, and rtog's map against that truth.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <unordered_set>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/sim/calibration.hpp"
#include "rtog/sim/metrics.hpp"
#include "rtog/sim/sensors.hpp"
#include "rtog/sim/world.hpp"

using namespace rtog;
using namespace rtog::sim;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Independent reference: the entry parameter of the ray into a closed box by the slab method,
// per axis the interval of t where the ray is between the two planes.
double slabEntry(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const SolidBox& b) {
  double lo = 0.0, hi = kInf;
  for (int a = 0; a < 3; ++a) {
    double t_a0, t_a1;
    if (d[a] > 0) {
      t_a0 = (b.min[a] - o[a]) / d[a];
      t_a1 = (b.max[a] - o[a]) / d[a];
    } else if (d[a] < 0) {
      t_a0 = (b.max[a] - o[a]) / d[a];
      t_a1 = (b.min[a] - o[a]) / d[a];
    } else if (b.min[a] <= o[a] && o[a] <= b.max[a]) {
      continue;
    } else {
      return kInf;
    }
    lo = std::max(lo, t_a0);
    hi = std::min(hi, t_a1);
  }
  return lo <= hi ? lo : kInf;
}

double bruteFirstHit(const World& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = kInf;
  for (const auto& b : w.boxes()) best = std::min(best, slabEntry(o, d, b));
  return best;
}

const WorldParams kParams{};
constexpr std::uint32_t kSeed = 42;

}  // namespace

TEST(SimWorld, RayCastMatchesBruteForce) {
  const World w = World::generate(kParams, kSeed);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(w.boundsMin().x() - 1, w.boundsMax().x() + 1),
      uy(w.boundsMin().y() - 1, w.boundsMax().y() + 1), uz(w.boundsMin().z() - 1, w.boundsMax().z() + 1);
  std::normal_distribution<double> n01;
  std::uniform_int_distribution<int> pick(0, static_cast<int>(w.trajectory().size()) - 1), axis(0, 5);
  int hits = 0, misses = 0;
  for (int i = 0; i < 200000; ++i) {
    Eigen::Vector3d o, d;
    // Half from sensor positions on the path (the realistic case), half from anywhere
    // (outside the world, inside walls); one in eight along a coordinate axis.
    if (i % 2 == 0) {
      o = w.trajectory()[static_cast<std::size_t>(pick(rng))].position + Eigen::Vector3d(0, 0, 1.2);
    } else {
      o = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
    }
    if (i % 8 == 3) {
      const int a = axis(rng);
      d = Eigen::Vector3d::Zero();
      d[a % 3] = a < 3 ? 1.0 : -1.0;
    } else {
      d = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized();
    }
    const double max_range = 30.0;
    const double ref = bruteFirstHit(w, o, d);
    const auto got = w.castRay(o, d, max_range);
    if (ref > max_range) {
      ASSERT_FALSE(got.has_value()) << "ray " << i << " hit at " << got->t << ", brute force says none";
      ++misses;
    } else {
      ASSERT_TRUE(got.has_value()) << "ray " << i << " missed, brute force hits at " << ref;
      // Two formulations of the slab test (multiply by 1/d vs divide) agree to rounding.
      ASSERT_NEAR(got->t, ref, 1e-12 * (1 + ref)) << "ray " << i;
      ASSERT_NEAR(slabEntry(o, d, w.boxes()[got->box]), ref, 1e-12 * (1 + ref))
          << "ray " << i << ": reported box is not hit there";
      ++hits;
    }
  }
  EXPECT_GT(hits, 100000);
  EXPECT_GT(misses, 1000);
}

TEST(SimWorld, DeterministicForASeed) {
  const World a = World::generate(kParams, kSeed), b = World::generate(kParams, kSeed);
  ASSERT_EQ(a.boxes().size(), b.boxes().size());
  for (std::size_t i = 0; i < a.boxes().size(); ++i) {
    EXPECT_EQ(a.boxes()[i].min, b.boxes()[i].min);
    EXPECT_EQ(a.boxes()[i].max, b.boxes()[i].max);
    EXPECT_EQ(a.boxes()[i].kind, b.boxes()[i].kind);
  }
  ASSERT_EQ(a.trajectory().size(), b.trajectory().size());
  for (std::size_t i = 0; i < a.trajectory().size(); ++i) {
    EXPECT_EQ(a.trajectory()[i].position, b.trajectory()[i].position);
    EXPECT_EQ(a.trajectory()[i].yaw, b.trajectory()[i].yaw);
  }
  const SimulatedLog la = simulate(a, LidarParams{}, ScannerParams{}, 1, 2, 8);
  const SimulatedLog lb = simulate(b, LidarParams{}, ScannerParams{}, 1, 2, 8);
  ASSERT_EQ(la.lidar.size(), lb.lidar.size());
  for (std::size_t s = 0; s < la.lidar.size(); ++s) {
    EXPECT_EQ(la.lidar[s].points, lb.lidar[s].points);
    EXPECT_EQ(la.lidar[s].is_hit, lb.lidar[s].is_hit);
    EXPECT_EQ(la.planar[s].points, lb.planar[s].points);
  }
  // Another seed gives another world; another noise seed other ranges, same truth.
  const World c = World::generate(kParams, kSeed + 1);
  EXPECT_TRUE(c.boxes().size() != a.boxes().size() || c.boxes()[2].max != a.boxes()[2].max);
  const SimulatedLog lc = simulate(a, LidarParams{}, ScannerParams{}, 3, 4, 8);
  EXPECT_NE(la.lidar[0].range, lc.lidar[0].range);
  EXPECT_EQ(la.lidar[0].true_range, lc.lidar[0].true_range);
}

TEST(SimWorld, WorldIsWellFormed) {
  const World w = World::generate(kParams, kSeed);
  ASSERT_GT(w.trajectory().size(), 20u);
  // The sensors never stand inside an obstacle, and consecutive poses are close.
  for (std::size_t i = 0; i < w.trajectory().size(); ++i) {
    const Eigen::Vector3d p = w.trajectory()[i].position;
    EXPECT_FALSE(w.containsPoint(p + Eigen::Vector3d(0, 0, 0.3))) << "pose " << i;
    EXPECT_FALSE(w.containsPoint(p + Eigen::Vector3d(0, 0, 1.2))) << "pose " << i;
    if (i) {
      EXPECT_LE((p - w.trajectory()[i - 1].position).norm(), kParams.pose_spacing + 1e-9);
    }
  }
}

TEST(SimSensors, NoiseStatistics) {
  const World w = World::generate(kParams, kSeed);
  for (const double sigma : {0.01, 0.05}) {
    LidarParams lp;
    lp.sigma = sigma;
    ScannerParams sp;
    sp.sigma = sigma;
    const SimulatedLog log = simulate(w, lp, sp, 11, 12, 2);
    for (int which = 0; which < 2; ++which) {
      double sum = 0, sum2 = 0;
      std::size_t n = 0;
      for (const Scan& s : which == 0 ? log.lidar : log.planar)
        for (std::size_t i = 0; i < s.range.size(); ++i) {
          // Beams near max range are cut by it (biased); leave them out.
          if (!(s.true_range[i] < lp.max_range - 6 * sigma)) continue;
          ASSERT_TRUE(s.is_hit[i]);
          const double e = double{s.range[i]} - double{s.true_range[i]};
          sum += e;
          sum2 += e * e;
          ++n;
        }
      ASSERT_GT(n, 5000u);
      const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
      // Float ranges add ~1e-7 relative error; 5 standard errors of the estimates.
      EXPECT_LT(std::abs(mean), 5 * sigma / std::sqrt(double(n))) << (which ? "2D" : "3D") << " sigma " << sigma;
      EXPECT_NEAR(sd / sigma, 1.0, 5 / std::sqrt(2.0 * n)) << (which ? "2D" : "3D") << " sigma " << sigma;
    }
  }
  // Noise-free: the measured range is the exact one and the point lies on a box surface.
  LidarParams exact;
  exact.sigma = 0;
  Lidar3D lidar(exact);
  const Scan s = lidar.scan(w, w.trajectory()[3]);
  for (std::size_t i = 0; i < s.range.size(); ++i)
    if (s.is_hit[i]) {
      ASSERT_EQ(s.range[i], s.true_range[i]);
    }
}

TEST(SimSensors, DisplacedScanIsTheScanAtTheBelievedPose) {
  const World w = World::generate(kParams, kSeed);
  LidarParams lp;
  lp.azimuth_steps = 64;
  Lidar3D lidar(lp, 5);
  const Pose pose = w.trajectory()[5];
  const Scan s = lidar.scan(w, pose);
  const PoseError e{0.07, -0.03, 0.02};
  const Scan d = displaced(s, e);
  ASSERT_EQ(d.points.size(), s.points.size());
  EXPECT_EQ(d.is_hit, s.is_hit);
  EXPECT_EQ(d.range, s.range);
  EXPECT_NEAR((d.origin - s.origin - Eigen::Vector3d(e.dx, e.dy, 0)).norm(), 0.0, 1e-12);
  // Beam i of the believed scan leaves the believed pose along the sensor's direction i turned
  // by the believed heading, and ends at the measured range.
  const double yaw = pose.yaw + e.dyaw;
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    const Eigen::Vector3d& u = lidar.directions()[i];
    const Eigen::Vector3d dir(std::cos(yaw) * u.x() - std::sin(yaw) * u.y(), std::sin(yaw) * u.x() + std::cos(yaw) * u.y(), u.z());
    const Eigen::Vector3d expect = d.origin + dir * double{s.range[i]};
    ASSERT_LT((d.points[i].cast<double>() - expect).norm(), 1e-5) << i;
  }
  // The inverse error brings it back.
  const Scan back = displaced(d, PoseError{-e.dx, -e.dy, 0.0});
  const Scan back2 = displaced(back, PoseError{0.0, 0.0, -e.dyaw});
  for (std::size_t i = 0; i < s.points.size(); ++i) ASSERT_LT((back2.points[i] - s.points[i]).norm(), 1e-5f) << i;
}

TEST(SimSensors, PoseErrorStatistics) {
  const std::vector<PoseError> a = samplePoseErrors(20000, 0.05, 0.02, 9);
  EXPECT_EQ(samplePoseErrors(20000, 0.05, 0.02, 9).back().dyaw, a.back().dyaw);  // seeded
  double sx = 0, sxx = 0, syy = 0, saa = 0, sxa = 0;
  for (const auto& e : a) {
    sx += e.dx;
    sxx += e.dx * e.dx;
    syy += e.dy * e.dy;
    saa += e.dyaw * e.dyaw;
    sxa += e.dx * e.dyaw;
  }
  const double n = static_cast<double>(a.size());
  EXPECT_LT(std::abs(sx / n), 5 * 0.05 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sxx / n) / 0.05, 1.0, 5 / std::sqrt(2 * n));
  EXPECT_NEAR(std::sqrt(syy / n) / 0.05, 1.0, 5 / std::sqrt(2 * n));
  EXPECT_NEAR(std::sqrt(saa / n) / 0.02, 1.0, 5 / std::sqrt(2 * n));
  EXPECT_LT(std::abs(sxa / n) / (0.05 * 0.02), 5 / std::sqrt(n));  // independent
  EXPECT_TRUE(samplePoseErrors(3, 0, 0, 1)[2].dx == 0.0);
  EXPECT_THROW(samplePoseErrors(3, -1, 0, 1), std::invalid_argument);
  EXPECT_THROW(samplePoseErrors(3, 0.1, 0, 1, 1.0), std::invalid_argument);
  EXPECT_THROW(samplePoseErrors(3, 0.1, 0, 1, -0.1), std::invalid_argument);
  // Correlated: the same marginal sigma, and consecutive errors correlate by rho.
  const double rho = 0.9;
  const std::vector<PoseError> c = samplePoseErrors(40000, 0.05, 0.02, 10, rho);
  double cxx = 0, cx1 = 0, caa = 0;
  for (std::size_t k = 0; k + 1 < c.size(); ++k) {
    cxx += c[k].dx * c[k].dx;
    cx1 += c[k].dx * c[k + 1].dx;
    caa += c[k].dyaw * c[k].dyaw;
  }
  const double m = static_cast<double>(c.size() - 1);
  // An AR(1) sequence has about n (1 - rho^2) / (1 + rho^2) effective samples for its variance.
  const double eff = m * (1 - rho * rho) / (1 + rho * rho);
  EXPECT_NEAR(std::sqrt(cxx / m) / 0.05, 1.0, 5 / std::sqrt(2 * eff));
  EXPECT_NEAR(std::sqrt(caa / m) / 0.02, 1.0, 5 / std::sqrt(2 * eff));
  EXPECT_NEAR(cx1 / cxx, rho, 0.01);
  EXPECT_THROW(samplePoseErrors(3, 0, std::nan(""), 1), std::invalid_argument);
}

TEST(SimTruth, RasterMatchesPerCellTruthAndHitPoints) {
  const World w = World::generate(kParams, kSeed);
  const Lattice lat(0.1);
  const Box region = worldKeyBox(w, lat, 2);
  const TruthGrid g = TruthGrid::rasterize(w, lat, region);
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::size_t> any(0, g.size() - 1);
  for (int i = 0; i < 100000; ++i) {
    const std::size_t c = any(rng);
    ASSERT_EQ(g.occupiedAt(c), w.cellOccupied(lat, g.key(c))) << toString(g.key(c));
  }
  // Every exact end point lies on a surface: its cell intersects a box.
  LidarParams exact;
  exact.sigma = 0;
  Lidar3D lidar(exact);
  std::size_t n = 0, on = 0;
  for (std::size_t p = 0; p < w.trajectory().size(); p += 10) {
    const Scan s = lidar.scan(w, w.trajectory()[p]);
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      if (!s.is_hit[i]) continue;
      ++n;
      on += g.occupied(lat.key(s.points[i].cast<double>()));
    }
  }
  // Float end points may round into the free neighbour when a face is within ~1e-6 m of a cell boundary.
  EXPECT_GE(static_cast<double>(on), 0.999 * static_cast<double>(n));
}

TEST(SimMetrics, PrecisionRecallAuc) {
  Evaluator ev;
  ev.add(0.9, Predicted::Occupied, true);
  ev.add(0.8, Predicted::Occupied, false);
  ev.add(0.3, Predicted::Free, true);
  ev.add(0.2, Predicted::Free, false);
  ev.add(0.9, Predicted::Unknown, false);  // scored as 0.5
  const ClassMetrics m = ev.finish();
  EXPECT_EQ(m.cells, 5u);
  EXPECT_DOUBLE_EQ(m.precision_occupied, 0.5);
  EXPECT_DOUBLE_EQ(m.recall_occupied, 0.5);
  EXPECT_DOUBLE_EQ(m.precision_free, 0.5);
  EXPECT_DOUBLE_EQ(m.recall_free, 1.0 / 3.0);
  // Positives {0.9, 0.3}, negatives {0.8, 0.5, 0.2}: pairs ranked right 0.9>all (3), 0.3>0.2 (1) -> 4/6.
  EXPECT_DOUBLE_EQ(m.auc, 4.0 / 6.0);
  EXPECT_EQ(m.roc.front(), std::make_pair(0.0, 0.0));
  EXPECT_EQ(m.roc.back(), std::make_pair(1.0, 1.0));
}

// Brier score, NLL and ECE of the same five cells, by hand: P = {0.9, 0.8, 0.3, 0.2, 0.5 (unknown)},
// truth = {1, 0, 1, 0, 0}.
TEST(SimMetrics, CalibrationFigures) {
  Evaluator ev;
  ev.add(0.9, Predicted::Occupied, true);
  ev.add(0.8, Predicted::Occupied, false);
  ev.add(0.3, Predicted::Free, true);
  ev.add(0.2, Predicted::Free, false);
  ev.add(0.9, Predicted::Unknown, false);
  const ClassMetrics m = ev.finish();
  EXPECT_NEAR(m.brier, (0.01 + 0.64 + 0.49 + 0.04 + 0.25) / 5, 1e-15);
  EXPECT_NEAR(m.nll, -(std::log(0.9) + std::log(0.2) + std::log(0.3) + std::log(0.8) + std::log(0.5)) / 5, 1e-15);
  // Bins: [0.2,0.3) {0.2: free}, [0.3,0.4) {0.3: occupied}, [0.5,0.6) {0.5: free}, [0.8,0.9) {0.8: free},
  // [0.9,1] {0.9: occupied}: each one cell, |p - share| = 0.2, 0.7, 0.5, 0.8, 0.1.
  EXPECT_NEAR(m.ece, (0.2 + 0.7 + 0.5 + 0.8 + 0.1) / 5, 1e-12);
  ASSERT_EQ(m.reliability.size(), std::size_t(kCalibrationBins));
  EXPECT_EQ(m.reliability[3].cells, 1u);
  EXPECT_DOUBLE_EQ(m.reliability[3].occupied_share, 1.0);
  EXPECT_EQ(m.reliability[0].cells, 0u);
  // A perfectly calibrated predictor: P = 0.25 on cells a quarter of which are occupied.
  Evaluator cal;
  for (int i = 0; i < 400; ++i) cal.add(0.25, Predicted::Free, i % 4 == 0);
  EXPECT_NEAR(cal.finish().ece, 0.0, 1e-12);
}

// rtog built from exact scans must call the occupied cells it saw occupied: of the truth-occupied
// cells that hold an exact end point, >= 95 % must be Occupied in the map (the rest were crossed
// by grazing beams of other scans more often than hit). Precision must be perfect.
TEST(SimAccuracy, RtogClassifiesObservedOccupiedCells) {
  const World w = World::generate(kParams, kSeed);
  LidarParams lp;
  lp.sigma = 0;
  const SimulatedLog log = simulate(w, lp, ScannerParams{}, 1, 2, 2);
  MapParams mp;
  mp.resolution = 0.1;
  OccupancyMap map(mp);
  InsertParams ip;
  ip.max_range = lp.max_range;
  std::unordered_set<Key, KeyHash> hit_cells;
  for (const Scan& s : log.lidar) {
    map.insertPointCloud(s.origin, s.points.data(), s.points.size(), ip, s.is_hit.data());
    for (std::size_t i = 0; i < s.points.size(); ++i)
      if (s.is_hit[i]) hit_cells.insert(map.lattice().key(s.points[i].cast<double>()));
  }
  const TruthGrid g = TruthGrid::rasterize(w, map.lattice(), worldKeyBox(w, map.lattice(), 2));
  std::size_t seen = 0, seen_occ = 0, known_truth_occ = 0, known_truth_occ_occ = 0, called_occ = 0, called_occ_true = 0;
  for (const Key& k : hit_cells) {
    if (!g.occupied(k)) continue;
    ++seen;
    seen_occ += map.state(k) == CellState::Occupied;
  }
  map.forEachLeaf([&](const Box& b, float v) {
    forEachCell(b, [&](const Key& k) {
      const bool occ = map.logOddsModel().classify(v) == CellState::Occupied;
      if (g.occupied(k)) {
        ++known_truth_occ;
        known_truth_occ_occ += occ;
      }
      if (occ) {
        ++called_occ;
        called_occ_true += g.occupied(k);
      }
    });
  });
  const double hit_fraction = double(seen_occ) / double(seen);
  const double known_fraction = double(known_truth_occ_occ) / double(known_truth_occ);
  RecordProperty("occupied_hit_cells", static_cast<int>(seen));
  std::printf("truth-occupied cells holding an end point: %zu, Occupied in rtog: %.4f\n", seen, hit_fraction);
  std::printf("truth-occupied cells rtog knows: %zu, Occupied: %.4f\n", known_truth_occ, known_fraction);
  std::printf("cells rtog calls Occupied: %zu, truly occupied: %.6f\n", called_occ,
              double(called_occ_true) / double(called_occ));
  ASSERT_GT(seen, 10000u);
  EXPECT_GE(hit_fraction, 0.95);
  EXPECT_EQ(called_occ_true, called_occ);
}

// The rates a calibration measures: exact scans end in occupied cells and cross free ones; range
// noise moves end points off the surface and into walls, so both rates move towards 0.5.
TEST(SimCalibration, ExactScansGiveSharpRatesAndNoiseBlursThem) {
  const World w = World::generate(kParams, kSeed);
  const Lattice lat(0.1);
  const TruthGrid truth = TruthGrid::rasterize(w, lat, worldKeyBox(w, lat, 2));
  InverseModelRates rate[2];
  std::size_t hits[2] = {0, 0};
  for (int noisy = 0; noisy < 2; ++noisy) {
    LidarParams lp;
    lp.sigma = noisy ? 0.05 : 0.0;
    lp.azimuth_steps = 360;
    Lidar3D lidar(lp, 9);
    std::vector<Scan> scans;
    for (std::size_t p = 0; p < w.trajectory().size(); p += 20) scans.push_back(lidar.scan(w, w.trajectory()[p]));
    for (const Scan& s : scans) hits[noisy] += s.hits();
    rate[noisy] = measureInverseModel(truth, lat, scans);
  }
  // Every return is a hit sample (the region holds the whole world), and a beam crosses many cells.
  EXPECT_EQ(rate[0].end_cells, hits[0]);
  EXPECT_EQ(rate[1].end_cells, hits[1]);
  EXPECT_GT(rate[0].crossed_cells, 10 * rate[0].end_cells);
  EXPECT_GE(rate[0].prob_hit, 0.999);
  EXPECT_LT(rate[0].prob_miss, 0.02);
  EXPECT_LT(rate[1].prob_hit, rate[0].prob_hit - 0.05);
  EXPECT_GT(rate[1].prob_miss, rate[0].prob_miss);
  EXPECT_THROW(measureInverseModel(truth, lat, {}), std::invalid_argument);
}
