// Pose blur by moving one trace (OccupancyMap::insertBlurred with PoseMove): for moves by whole
// cells the moved trace is each pose's own trace, so the map equals the blur traced pose by pose
// bit for bit; under turns it differs only by the raster, on few cells and by little; one pose
// moved by nothing is the plain update; Auto moves dense scans and traces sparse ones; the map
// does not depend on the thread count; bad input changes nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>

#include "map_cells.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "test_support.hpp"

using namespace rtog;

namespace {

using test::CellValues;
using test::cellsOf;

MapParams params(double res) {
  MapParams p;
  p.resolution = res;
  p.merge = MergePolicy::Equal;
  return p;
}

InsertParams model(SensorModel m, int threads = 1, BlurMethod how = BlurMethod::Move) {
  InsertParams ip;
  ip.model = m;
  ip.blur_method = how;
  ip.max_range = 4.0;
  ip.threads = threads;
  return ip;
}

// A TUM frame with its coordinates on a 2^-10 m grid, so that moving it by whole cells of a
// power-of-two size is exact in floating point: the traced poses then see exactly moved beams.
struct Frame {
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> points;
};
Frame snapped(const image::WorldScan& s) {
  const auto snap = [](double v) { return std::round(v * 1024.0) / 1024.0; };
  Frame f{s.origin.unaryExpr(snap), {}};
  for (const auto& p : s.points) f.points.push_back(p.cast<double>().unaryExpr(snap).cast<float>());
  return f;
}

PoseMove shift(double w, double dx, double dy, double dz) {
  PoseMove m;
  m.weight = w;
  m.move.translation() = Eigen::Vector3d(dx, dy, dz);
  return m;
}
// The poses' scans, each moved whole, for the blur traced pose by pose.
struct Traced {
  std::vector<std::vector<Eigen::Vector3f>> points;
  std::vector<WeightedScan> scans;
};
Traced traced(const Frame& f, const std::vector<PoseMove>& moves) {
  Traced t;
  t.points.resize(moves.size());
  for (std::size_t i = 0; i < moves.size(); ++i)
    for (const auto& p : f.points) t.points[i].push_back((moves[i].move * p.cast<double>()).cast<float>());
  for (std::size_t i = 0; i < moves.size(); ++i)
    t.scans.push_back(WeightedScan{moves[i].weight, moves[i].move * f.origin, t.points[i].data(), t.points[i].size(), nullptr});
  return t;
}

bool sameCells(const CellValues& a, const CellValues& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].first != b[i].first || std::memcmp(&a[i].second, &b[i].second, sizeof(float)) != 0) return false;
  return true;
}

const std::vector<SensorModel> kModels = {SensorModel::BeamBased, SensorModel::BeamEndPoint, SensorModel::RangeNoise};

}  // namespace

TEST(PoseResample, MovesByWholeCellsEqualTheBlurTracedPoseByPoseBitForBit) {
  const auto frames = test::loadTumScans(8);
  ASSERT_GE(frames.size(), 3u);
  const double res = 0.0625;
  const std::vector<PoseMove> moves = {shift(0.1, 2 * res, 0, 0), shift(0.2, -3 * res, res, 0),
                                       shift(0.3, 0, -res, 2 * res), shift(0.4, 0, 0, 0)};
  for (const SensorModel m : kModels) {
    OccupancyMap by_pose(params(res)), moved(params(res)), retraced(params(res));
    for (std::size_t k = 0; k < 3; ++k) {
      const Frame f = snapped(frames[k]);
      const Traced t = traced(f, moves);
      by_pose.insertBlurred(t.scans, model(m));
      moved.insertBlurred(f.origin, f.points, moves, model(m));
      retraced.insertBlurred(f.origin, f.points, moves, model(m, 1, BlurMethod::Trace));
    }
    ASSERT_EQ(moved.checkInvariants(), "");
    const CellValues a = cellsOf(by_pose), b = cellsOf(moved);
    EXPECT_GT(a.size(), 5000u);
    EXPECT_TRUE(sameCells(a, b)) << toString(m) << ": " << a.size() << " against " << b.size() << " cells";
    EXPECT_TRUE(sameCells(a, cellsOf(retraced))) << toString(m);
  }
}

TEST(PoseResample, NoMoveIsThePlainUpdate) {
  const auto frames = test::loadTumScans(8);
  for (const SensorModel m : kModels) {
    OccupancyMap plain(params(0.1)), moved(params(0.1));
    plain.insertPointCloud(frames[1].origin, frames[1].points, model(m));
    moved.insertBlurred(frames[1].origin, frames[1].points, {PoseMove{}, PoseMove{}, PoseMove{}}, model(m));
    const CellValues a = cellsOf(plain), b = cellsOf(moved);
    ASSERT_EQ(a.size(), b.size()) << toString(m);
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].first, b[i].first);
      EXPECT_NEAR(a[i].second, b[i].second, 1e-5);
    }
  }
}

// Under turns a moved trace is not a traced one: a beam's cells moved are not the moved beam's
// cells. The two blurs must still agree on nearly every cell (the same cells known, nearly the
// same probabilities), here for a sigma set of x, y and a turn of 2 degrees on real frames.
TEST(PoseResample, UnderTurnsDiffersFromTheTracedBlurOnlyByTheRaster) {
  const auto frames = test::loadTumScans(8);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(3, 3);
  cov(0, 0) = cov(1, 1) = 0.05 * 0.05;
  cov(2, 2) = std::pow(2.0 * M_PI / 180.0, 2);
  for (const SensorModel m : {SensorModel::BeamBased, SensorModel::RangeNoise}) {
    OccupancyMap by_pose(params(0.05)), moved(params(0.05));
    for (std::size_t k = 0; k < 4; ++k) {
      const Frame f{frames[k].origin, frames[k].points};
      std::vector<PoseMove> moves;
      for (const SigmaPoint& s : sigmaPoints(cov)) moves.push_back(planarMove(s.weight, f.origin, s.offset[0], s.offset[1], s.offset[2]));
      const Traced t = traced(f, moves);
      by_pose.insertBlurred(t.scans, model(m));
      moved.insertBlurred(f.origin, f.points, moves, model(m));
    }
    ASSERT_EQ(moved.checkInvariants(), "");
    std::map<std::uint64_t, float> a;
    for (const auto& [k, v] : cellsOf(by_pose)) a[k] = v;
    const CellValues b = cellsOf(moved);
    std::size_t shared = 0, far = 0;
    double diff = 0;
    for (const auto& [k, v] : b) {
      const auto it = a.find(k);
      if (it == a.end()) continue;
      ++shared;
      const double dp = std::abs(1 / (1 + std::exp(-double(v))) - 1 / (1 + std::exp(-double(it->second))));
      diff += dp;
      far += dp > 0.1;
    }
    const double known = double(std::max(a.size(), b.size()));
    EXPECT_GT(double(shared), 0.98 * known) << toString(m);
    EXPECT_LT(diff / double(shared), 0.01) << toString(m);
    EXPECT_LT(double(far), 0.02 * double(shared)) << toString(m);
    std::printf("%s: %zu cells traced, %zu moved, %zu in both, mean |dP| %.4f, %zu over 0.1\n", toString(m),
                a.size(), b.size(), shared, diff / double(shared), far);
  }
}

TEST(PoseResample, TheMapDoesNotDependOnTheThreadCount) {
  const auto frames = test::loadTumScans(8);
  std::vector<PoseMove> moves;
  for (int i = 0; i < 6; ++i) moves.push_back(planarMove(1.0, frames[2].origin, 0.03 * (i - 2.5), 0.01 * i, 0.01 * (i % 3 - 1)));
  for (const SensorModel m : {SensorModel::BeamBased, SensorModel::RangeNoise}) {
    CellValues ref;
    for (const int threads : {1, 2, 5}) {
      OccupancyMap map(params(0.05));
      map.insertBlurred(frames[2].origin, frames[2].points, moves, model(m, threads));
      const CellValues c = cellsOf(map);
      if (ref.empty()) ref = c;
      EXPECT_TRUE(sameCells(c, ref)) << toString(m) << ", " << threads << " threads";
    }
  }
}

// Auto moves a depth image's trace (its beams cross each cell ~150 times at 5 cm) and traces a
// LiDAR-like scan's poses (a ring of long beams, crossing each cell about once).
TEST(PoseResample, AutoMovesDenseScansAndTracesSparseOnes) {
  const auto dense = test::loadTumScans(1);
  image::WorldScan ring;
  ring.origin = Eigen::Vector3d(0.3, -0.2, 0.5);
  for (int k = 0; k < 720; ++k) {
    const double a = k * M_PI / 360.0;
    ring.points.push_back((ring.origin + Eigen::Vector3d(3.5 * std::cos(a), 3.5 * std::sin(a), 0.1 * std::sin(3 * a))).cast<float>());
  }
  for (const auto& [scan, want] : {std::pair{dense[0], BlurMethod::Move}, std::pair{ring, BlurMethod::Trace}}) {
    std::vector<PoseMove> moves;
    for (int i = 0; i < 4; ++i) moves.push_back(planarMove(1.0, scan.origin, 0.02 * (i - 1.5), 0.01 * i, 0.01 * (i % 2)));
    OccupancyMap automatic(params(0.05)), chosen(params(0.05)), other(params(0.05));
    const BlurMethod not_want = want == BlurMethod::Move ? BlurMethod::Trace : BlurMethod::Move;
    automatic.insertBlurred(scan.origin, scan.points, moves, model(SensorModel::BeamBased, 1, BlurMethod::Auto));
    chosen.insertBlurred(scan.origin, scan.points, moves, model(SensorModel::BeamBased, 1, want));
    other.insertBlurred(scan.origin, scan.points, moves, model(SensorModel::BeamBased, 1, not_want));
    EXPECT_TRUE(sameCells(cellsOf(automatic), cellsOf(chosen)));
    EXPECT_FALSE(sameCells(cellsOf(automatic), cellsOf(other)));  // the two ways differ by their rasters
  }
}

TEST(PoseResample, BadWeightsMovesOrOriginsChangeNothing) {
  const auto frames = test::loadTumScans(8);
  OccupancyMap map(params(0.1));
  map.insertPointCloud(frames[0].origin, frames[0].points, model(SensorModel::BeamBased));
  const CellValues before = cellsOf(map);
  const auto& f = frames[1];
  for (const double bad : {0.0, -1.0, std::nan(""), HUGE_VAL})
    EXPECT_THROW(map.insertBlurred(f.origin, f.points, {PoseMove{}, shift(bad, 0, 0, 0)}, model(SensorModel::BeamBased)),
                 std::invalid_argument);
  PoseMove nan;
  nan.move.translation().x() = std::nan("");
  EXPECT_THROW(map.insertBlurred(f.origin, f.points, {PoseMove{}, nan}, model(SensorModel::BeamBased)), std::invalid_argument);
  EXPECT_THROW(map.insertBlurred(f.origin, f.points, {PoseMove{}, shift(1.0, 1e12, 0, 0)}, model(SensorModel::BeamBased)),
               std::out_of_range);
  EXPECT_THROW(map.insertBlurred(Eigen::Vector3d(1e12, 0, 0), f.points, {PoseMove{}}, model(SensorModel::BeamBased)),
               std::out_of_range);
  EXPECT_TRUE(sameCells(before, cellsOf(map)));
  // No moves: nothing to insert.
  EXPECT_NO_THROW(map.insertBlurred(f.origin, f.points, std::vector<PoseMove>{}, model(SensorModel::BeamBased)));
  EXPECT_TRUE(sameCells(before, cellsOf(map)));
}
