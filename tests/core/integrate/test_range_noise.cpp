// The range-noise inverse model (doc/range-noise.md): sigma 0 is the beam model cell for cell
// on real frames, small sigma approaches it, and along one beam each cell holds the value the
// derivation gives, computed here independently by integrating the Gaussian numerically.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "rtog/core/occupancy_map.hpp"
#include "map_cells.hpp"
#include "test_support.hpp"

using namespace rtog;

namespace {

using test::CellValues;
using test::cellsOf;

// Cells whose presence or value differ between two maps.
std::size_t differingCells(const CellValues& a, const CellValues& b) {
  std::size_t diff = 0, i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && a[i].first < b[j].first)) {
      ++diff, ++i;
    } else if (i == a.size() || b[j].first < a[i].first) {
      ++diff, ++j;
    } else {
      diff += std::memcmp(&a[i].second, &b[j].second, sizeof(float)) != 0;
      ++i, ++j;
    }
  }
  return diff;
}

MapParams coarse() {
  MapParams p;
  p.resolution = 0.1;
  p.merge = MergePolicy::Equal;
  return p;
}

CellValues buildTum(InsertParams ip) {
  OccupancyMap m(coarse());
  for (const auto& s : test::loadTumScans(8)) m.insertPointCloud(s.origin, s.points, ip);
  EXPECT_EQ(m.checkInvariants(), "");
  return cellsOf(m);
}

InsertParams rangeNoise(double std, double per_meter = 0.0) {
  InsertParams ip;
  ip.model = SensorModel::RangeNoise;
  ip.range_noise_std = std;
  ip.range_noise_std_per_meter = per_meter;
  return ip;
}

TEST(RangeNoise, ZeroSigmaIsTheBeamModelCellForCellOnRealFrames) {
  const CellValues beam = buildTum(InsertParams{});
  ASSERT_GT(beam.size(), 50000u);
  EXPECT_EQ(differingCells(beam, buildTum(rangeNoise(0.0))), 0u);
}

TEST(RangeNoise, SmallSigmaApproachesTheBeamModelOnRealFrames) {
  const CellValues beam = buildTum(InsertParams{});
  std::size_t last = beam.size();
  for (const double sigma : {0.1, 0.01, 1e-3, 1e-5, 1e-7}) {
    const std::size_t d = differingCells(beam, buildTum(rangeNoise(sigma)));
    std::printf("sigma %g m: %zu of %zu cells differ from the beam model's\n", sigma, d, beam.size());
    EXPECT_LE(d, last) << "sigma " << sigma;
    last = d;
    if (sigma == 0.1) {
      EXPECT_GT(d, beam.size() / 100) << "a real band changes many cells";
    }
  }
  EXPECT_LE(last, 2u) << "at 0.1 um only cells whose reading lies on a face may differ";
}

// P(occ | r) of the cell [a, b] by the derivation, integrated numerically (Simpson) here.
double expectedOccupancy(double a, double b, double r, double sigma, double k, const LogOddsParams& p) {
  const auto pdf = [&](double z) { return std::abs(z - r) > k * sigma ? 0.0 : std::exp(-0.5 * std::pow((z - r) / sigma, 2)); };
  const auto integral = [&](double lo, double hi) {
    if (hi <= lo) return 0.0;
    const int n = 20000;
    const double h = (hi - lo) / n;
    double s = pdf(lo) + pdf(hi);
    for (int i = 1; i < n; ++i) s += pdf(lo + i * h) * (i % 2 ? 4 : 2);
    return s * h / 3;
  };
  const double all = integral(r - k * sigma, r + k * sigma);
  const double behind = integral(r - k * sigma, std::max(a, r - k * sigma)) / all;
  const double in = integral(std::max(a, r - k * sigma), std::min(b, r + k * sigma)) / all;
  const double passed = 1.0 - behind - in;
  return in * p.prob_hit + passed * p.prob_miss + behind * p.prior;
}

TEST(RangeNoise, EachCellAlongABeamHoldsTheDerivedProbability) {
  MapParams mp;
  mp.resolution = 0.05;
  mp.merge = MergePolicy::Off;
  OccupancyMap m(mp);
  const double r = 3.013, sigma = 0.1, k = 3.0;
  const Eigen::Vector3d origin(0.0125, 0.0125, 0.0125);
  const std::vector<Eigen::Vector3f> end{Eigen::Vector3f(float(origin.x() + r), float(origin.y()), float(origin.z()))};
  const double r_true = double(end[0].x()) - origin.x();  // the float end point's range
  m.insertPointCloud(origin, end, rangeNoise(sigma));
  ASSERT_EQ(m.checkInvariants(), "");
  const LogOddsModel& model = m.logOddsModel();
  int band = 0;
  double last_p = 0.0, peak_at = 0.0, peak = 0.0;
  for (std::int32_t x = 0; x < 80; ++x) {
    const double a = std::max(0.0, x * 0.05 - origin.x()), b = (x + 1) * 0.05 - origin.x();
    const std::optional<float> v = m.logOdds(Key{x, 0, 0});
    if (a >= r_true + k * sigma) {
      EXPECT_FALSE(v) << "cell " << x << " lies behind the band";
      continue;
    }
    ASSERT_TRUE(v) << "cell " << x;
    if (b <= r_true - k * sigma) {
      EXPECT_EQ(*v, model.first(model.missDelta())) << "cell " << x << " lies before the band";
      continue;
    }
    ++band;
    const double p = expectedOccupancy(a, b, r_true, sigma, k, m.params().log_odds);
    const double l = std::log(p / (1 - p));
    EXPECT_NEAR(*v, l, 1e-5) << "cell " << x;
    if (p > peak) peak = p, peak_at = 0.5 * (a + b);
    if (0.5 * (a + b) < r_true - 0.05) {
      EXPECT_GE(p, last_p) << "P rises towards the reading, cell " << x;
    }
    last_p = p;
  }
  EXPECT_EQ(band, 13);  // 6 sigma over 5 cm cells, the edges' cells partly in
  // Being passed is evidence of free space, lying behind the surface none: the peak lies past
  // the reading, within about a sigma (doc/range-noise.md).
  EXPECT_GE(peak_at, r_true - 0.025);
  EXPECT_LE(peak_at, r_true + 1.5 * sigma);
  EXPECT_GT(peak, 0.5);
  EXPECT_LT(peak, m.params().log_odds.prob_hit);
}

TEST(RangeNoise, TheBandWidensWithRange) {
  const auto bandCells = [](double r) {
    OccupancyMap m(MapParams{});
    const std::vector<Eigen::Vector3f> end{Eigen::Vector3f(float(r), 0.0125f, 0.0125f)};
    m.insertPointCloud(Eigen::Vector3d(0.0125, 0.0125, 0.0125), end, rangeNoise(0.01, 0.02));
    const LogOddsModel& model = m.logOddsModel();
    int n = 0;
    m.forEachLeaf([&](const Box& b, float v) {
      if (v != model.first(model.missDelta()) && v != model.first(model.hitDelta())) n += b.max.x - b.min.x + 1;
    });
    return n;
  };
  const int near = bandCells(1.0), far = bandCells(6.0);
  EXPECT_GE(near, 2);
  EXPECT_GT(far, 2 * near);  // sigma 0.03 m against 0.13 m
}

// n beams from one origin that all end in the cell of `target`, spread over it.
std::vector<Eigen::Vector3f> beamsIntoOneCell(const Eigen::Vector3d& target, int n) {
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < n; ++i)
    pts.emplace_back(float(target.x() + 0.035 * std::sin(1.3 * i)), float(target.y() + 0.035 * std::cos(0.7 * i)),
                     float(target.z() + 0.035 * std::sin(2.1 * i + 0.5)));
  return pts;
}

// The cells of a map whose value is not the miss change's (the graded ones).
CellValues gradedCells(const OccupancyMap& m) {
  const float miss = m.logOddsModel().first(m.logOddsModel().missDelta());
  CellValues out;
  for (const auto& c : cellsOf(m))
    if (c.second != miss) out.push_back(c);
  return out;
}

TEST(RangeNoise, BeamsEndingInOneCellShareTheBandOfTheRayToItsCentre) {
  MapParams mp;
  mp.resolution = 0.125;
  mp.merge = MergePolicy::Off;
  // The centre of its cell, exact in float and double alike.
  const Eigen::Vector3d origin(0.03, 0.02, 0.01), target(3.1875, 1.3125, 0.4375);
  const InsertParams shared = rangeNoise(0.05, 0.01);
  InsertParams own = shared;
  own.range_noise_shared_band = 0;
  const auto build = [&](const std::vector<Eigen::Vector3f>& pts, const InsertParams& ip) {
    auto m = std::make_unique<OccupancyMap>(mp);
    m->insertPointCloud(origin, pts, ip);
    EXPECT_EQ(m->checkInvariants(), "");
    return m;
  };
  // Fewer beams than range_noise_shared_band: a band each, as with sharing off.
  const auto three = beamsIntoOneCell(target, 3);
  EXPECT_EQ(differingCells(cellsOf(*build(three, shared)), cellsOf(*build(three, own))), 0u);
  // Eight: their graded cells are those of the one ray to the cell's centre, value for value;
  // each beam still frees the cells before its own band.
  const auto eight = beamsIntoOneCell(target, 8);
  const auto centre = build({target.cast<float>()}, own);
  const auto grouped = build(eight, shared), apart = build(eight, own);
  ASSERT_GE(gradedCells(*centre).size(), 5u);
  EXPECT_EQ(differingCells(gradedCells(*grouped), gradedCells(*centre)), 0u);
  EXPECT_GT(differingCells(gradedCells(*apart), gradedCells(*centre)), 0u) << "the beams' own bands differ";
  EXPECT_GT(cellsOf(*grouped).size(), cellsOf(*centre).size()) << "the beams' own free cells";
}

TEST(RangeNoise, TheMapDoesNotDependOnTheThreadCount) {
  InsertParams one = rangeNoise(0.03, 0.01), two = one;
  one.threads = 1;
  two.threads = 2;
  EXPECT_EQ(differingCells(buildTum(one), buildTum(two)), 0u);
}

TEST(RangeNoise, BadParametersAreRefusedByNameAndChangeNothing) {
  OccupancyMap m(MapParams{});
  const std::vector<Eigen::Vector3f> end{Eigen::Vector3f(1.0f, 0.0f, 0.0f)};
  m.insertPointCloud(Eigen::Vector3d::Zero(), end, rangeNoise(0.05));
  const CellValues before = cellsOf(m);
  const auto refused = [&](InsertParams ip, const char* name) {
    try {
      m.insertPointCloud(Eigen::Vector3d::Zero(), end, ip);
      ADD_FAILURE() << "accepted bad " << name;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  refused(rangeNoise(-0.01), "range_noise_std");
  refused(rangeNoise(std::nan("")), "range_noise_std");
  refused(rangeNoise(0.05, std::numeric_limits<double>::infinity()), "range_noise_std_per_meter");
  InsertParams cut = rangeNoise(0.05);
  cut.range_noise_cutoff = 0.0;
  refused(cut, "range_noise_cutoff");
  EXPECT_EQ(differingCells(before, cellsOf(m)), 0u);
}

}  // namespace
