// rtog-simlog's run: the map read, the loop driven, each step's odometry and laser scan
// simulated and written. Every random number comes from one generator seeded by --seed, drawn in
// a fixed order, so a seed always gives the same bytes.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/serialization/archiveFrom_std_streams.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "rtog/app/output_files.hpp"
#include "simlog.hpp"
#include "rtog/image/picture.hpp"

namespace rtog::simlog {
namespace {

using mrpt::math::TPoint2D;
using mrpt::poses::CPose2D;

// The laser: a SICK LMS-like scanner on the robot's centre.
constexpr std::size_t kBeams = 361;       // over 180 deg: 0.5 deg apart
constexpr float kMaxRange = 80.0f;        // [m]
constexpr double kRangeStd = 0.01;        // [m]
// The odometry's error, per step: a calibration error the same at every step (wheel radius,
// wheel base) and a random part, both relative to what the robot did, plus a heading error that
// grows with distance (wheel slip).
constexpr double kDistanceBias = 0.01, kDistanceStd = 0.03;  // of the distance driven
constexpr double kLateralStd = 0.01;                         // of the distance driven
constexpr double kTurnBias = 0.01, kTurnStd = 0.03;           // of the angle turned
const double kTurnPerMetreStd = mrpt::DEG2RAD(1.0);          // [rad per m driven]
// One step every 0.1 s from a fixed start, so that the bytes depend on the seed only.
constexpr double kStartTime = 1136419200.0, kPeriod = 0.1;  // [s]

mrpt::maps::COccupancyGridMap2D readGridmap(const std::string& path) {
  mrpt::maps::COccupancyGridMap2D grid;
  mrpt::io::CFileGZInputStream f;  // zlib reads plain files too
  bool opened = false;
  try {
    opened = f.open(path);
  } catch (const std::exception&) {  // MRPT throws, with a call stack, for a missing file
  }
  if (!opened) throw std::runtime_error("cannot open gridmap " + path);
  try {
    auto ar = mrpt::serialization::archiveFrom(f);
    ar >> grid;
  } catch (const std::exception&) {
    throw std::runtime_error(path + " is not a gridmap (a serialized mrpt::maps::COccupancyGridMap2D)");
  }
  if (grid.getSizeX() < 3 || grid.getSizeY() < 3) throw std::runtime_error("gridmap " + path + " has no cells to drive in");
  return grid;
}

// The world the robot drives in: what the map knows free is free, everything else (walls and
// the parts the map never saw) is solid, so that beams stop there as they would at a wall.
mrpt::maps::COccupancyGridMap2D solidWorld(const mrpt::maps::COccupancyGridMap2D& grid) {
  mrpt::maps::COccupancyGridMap2D world = grid;
  for (unsigned y = 0; y < grid.getSizeY(); ++y)
    for (unsigned x = 0; x < grid.getSizeX(); ++x) world.setCell(int(x), int(y), grid.getCell(x, y) > 0.6f ? 1.0f : 0.0f);
  return world;
}

// The world as one byte a cell (1: free), and the exact range along a ray to its first solid
// cell. MRPT 2.5's laserScanSimulator is not used: it steps along the ray in fixed point, a fifth
// of a cell a step, its direction rounded to 1/1024 of a step, so beams lean by up to a quarter
// degree and one in six of the Malaga log's passes a wall's corner or stops short of a wall
// (test_simlog's EveryBeamEndsAtTheFirstWall).
struct FreeCells {
  int sx = 0, sy = 0;
  double x_min = 0, y_min = 0, res = 1;
  std::vector<unsigned char> free;

  explicit FreeCells(const mrpt::maps::COccupancyGridMap2D& world)
      : sx(int(world.getSizeX())), sy(int(world.getSizeY())), x_min(world.getXMin()), y_min(world.getYMin()),
        res(world.getResolution()), free(std::size_t(sx) * std::size_t(sy)) {
    for (int y = 0; y < sy; ++y)
      for (int x = 0; x < sx; ++x) free[std::size_t(y) * std::size_t(sx) + std::size_t(x)] = world.getCell(x, y) > 0.5f;
  }
  bool isFree(int x, int y) const {
    return x >= 0 && y >= 0 && x < sx && y < sy && free[std::size_t(y) * std::size_t(sx) + std::size_t(x)] != 0;
  }

  /// Distance [m] from (x, y) along `angle` to where the ray enters the first cell that is not
  /// free (cell by cell, none skipped: Amanatides & Woo); < 0 if there is none within max_range.
  double cast(double x, double y, double angle, double max_range) const {
    const double fx = (x - x_min) / res, fy = (y - y_min) / res, dx = std::cos(angle), dy = std::sin(angle);
    int cx = int(std::floor(fx)), cy = int(std::floor(fy));
    const int step_x = dx >= 0 ? 1 : -1, step_y = dy >= 0 ? 1 : -1;
    const double inf = std::numeric_limits<double>::infinity();
    const double delta_x = dx != 0 ? 1.0 / std::abs(dx) : inf, delta_y = dy != 0 ? 1.0 / std::abs(dy) : inf;
    double next_x = dx != 0 ? (step_x > 0 ? cx + 1 - fx : fx - cx) * delta_x : inf;
    double next_y = dy != 0 ? (step_y > 0 ? cy + 1 - fy : fy - cy) * delta_y : inf;
    const double max_t = max_range / res;
    for (double t = 0; t <= max_t;) {
      if (cx < 0 || cy < 0 || cx >= sx || cy >= sy) return -1.0;  // left the map: no echo
      if (!isFree(cx, cy)) return t > 0 ? t * res : -1.0;
      if (next_x < next_y) {
        t = next_x, next_x += delta_x, cx += step_x;
      } else {
        t = next_y, next_y += delta_y, cy += step_y;
      }
    }
    return -1.0;
  }
};

// The robot's poses: `n` equally spaced along the closed loop, the last back at the first, each
// facing along the loop.
std::vector<CPose2D> poses(const std::vector<TPoint2D>& loop, std::size_t n) {
  std::vector<double> at(loop.size() + 1, 0.0);  // arc length at each point
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const TPoint2D& b = loop[(i + 1) % loop.size()];
    at[i + 1] = at[i] + std::hypot(b.x - loop[i].x, b.y - loop[i].y);
  }
  const double length = at.back();
  auto point = [&](double s) {
    s = std::fmod(std::fmod(s, length) + length, length);
    const std::size_t i = std::size_t(std::upper_bound(at.begin(), at.end(), s) - at.begin()) - 1;
    const TPoint2D& a = loop[i];
    const TPoint2D& b = loop[(i + 1) % loop.size()];
    const double t = at[i + 1] > at[i] ? (s - at[i]) / (at[i + 1] - at[i]) : 0.0;
    return TPoint2D{a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t};
  };
  std::vector<CPose2D> out;
  for (std::size_t i = 0; i < n; ++i) {
    const double s = length * double(i) / double(n - 1);
    const TPoint2D p = point(s), ahead = point(s + 0.3), behind = point(s - 0.3);
    out.emplace_back(p.x, p.y, std::atan2(ahead.y - behind.y, ahead.x - behind.x));
  }
  return out;
}

// `scale` multiplies every error term (--odometry-noise).
CPose2D noisyOdometry(const CPose2D& moved, double scale, mrpt::random::CRandomGenerator& rng) {
  const double d = std::hypot(moved.x(), moved.y());
  const double k = 1.0 + scale * (kDistanceBias + kDistanceStd * rng.drawGaussian1D_normalized());
  const double lateral = scale * kLateralStd * d * rng.drawGaussian1D_normalized();
  const double turn = moved.phi() * (1.0 + scale * (kTurnBias + kTurnStd * rng.drawGaussian1D_normalized())) +
                      scale * kTurnPerMetreStd * d * rng.drawGaussian1D_normalized();
  return CPose2D(moved.x() * k, moved.y() * k + lateral, turn);
}

void writePng(const mrpt::maps::COccupancyGridMap2D& grid, const std::vector<TPoint2D>& loop, std::ostream& out) {
  const int sx = int(grid.getSizeX()), sy = int(grid.getSizeY());
  cv::Mat img(sy, sx, CV_8UC3);
  for (int y = 0; y < sy; ++y)
    for (int x = 0; x < sx; ++x) {
      const auto v = static_cast<unsigned char>(std::lround(255.0 * grid.getCell(x, y)));
      img.at<cv::Vec3b>(sy - 1 - y, x) = cv::Vec3b(v, v, v);
    }
  std::vector<cv::Point> pts;
  for (const TPoint2D& p : loop) pts.emplace_back(grid.x2idx(p.x), sy - 1 - grid.y2idx(p.y));
  cv::polylines(img, pts, true, cv::Scalar(0, 0, 255), 3);
  cv::circle(img, pts.front(), 12, cv::Scalar(0, 160, 0), -1);
  out << image::encodePng(img);
}

}  // namespace

void run(const Options& o, std::ostream& log) {
  if (o.scans < 2) throw std::invalid_argument("--scans must be at least 2, got " + std::to_string(o.scans));
  const mrpt::maps::COccupancyGridMap2D grid = readGridmap(o.gridmap);
  // Every output opened before the work, so that a bad path fails at once; written all or none.
  app::OutputSet files({{"gridmap", o.gridmap}});
  std::ostream& rawlog = files.add("rawlog", o.rawlog);
  std::ostream* gt = o.gt.empty() ? nullptr : &files.add("--gt", o.gt);
  std::ostream* png = o.png.empty() ? nullptr : &files.add("--png", o.png);

  const mrpt::maps::COccupancyGridMap2D world = solidWorld(grid);
  const FreeCells cells(world);
  std::vector<TPoint2D> loop = planLoop(world, o.loop, log);
  if (o.reverse) std::reverse(loop.begin(), loop.end());
  const std::vector<CPose2D> path = poses(loop, o.scans);

  mrpt::random::CRandomGenerator rng(o.seed);
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;  // MRPT's Gaussian model
  motion.gaussianModel.a1 = std::max(motion.gaussianModel.a1, o.odometry_noise * (kDistanceBias + kDistanceStd));
  motion.gaussianModel.a4 = std::max(motion.gaussianModel.a4, o.odometry_noise * (kTurnBias + kTurnStd));
  auto ar = mrpt::serialization::archiveFrom(rawlog);
  if (gt) *gt << std::fixed << std::setprecision(6);
  double length = 0.0, max_turn = 0.0;
  std::size_t hits = 0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const mrpt::Clock::time_point t = mrpt::Clock::fromDouble(kStartTime + kPeriod * double(i));
    const CPose2D moved = i == 0 ? CPose2D() : path[i] - path[i - 1];
    length += moved.norm();
    max_turn = std::max(max_turn, std::abs(moved.phi()));

    mrpt::obs::CActionRobotMovement2D move;
    move.timestamp = t;
    move.computeFromOdometry(i == 0 ? CPose2D() : noisyOdometry(moved, o.odometry_noise, rng), motion);
    mrpt::obs::CActionCollection actions;
    actions.insert(move);

    auto scan = mrpt::obs::CObservation2DRangeScan::Create();
    scan->sensorLabel = "LASER";
    scan->timestamp = t;
    scan->aperture = float(M_PI);
    scan->rightToLeft = true;
    scan->maxRange = kMaxRange;
    scan->stdError = float(kRangeStd);
    scan->resizeScan(kBeams);
    for (std::size_t b = 0; b < kBeams; ++b) {
      // MRPT's beam order: right to left, the first at -aperture/2.
      const double angle = path[i].phi() - M_PI / 2 + M_PI * double(b) / double(kBeams - 1);
      const double r = cells.cast(path[i].x(), path[i].y(), angle, kMaxRange);
      scan->setScanRangeValidity(b, r >= 0);
      scan->setScanRange(b, kMaxRange);
      if (r < 0) continue;
      ++hits;
      scan->setScanRange(b, float(std::clamp(r + kRangeStd * rng.drawGaussian1D_normalized(), 0.0, double(kMaxRange))));
    }
    mrpt::obs::CSensoryFrame frame;
    frame.insert(scan);
    ar << actions << frame;
    if (gt) *gt << mrpt::Clock::toDouble(t) << ' ' << path[i].x() << ' ' << path[i].y() << ' ' << path[i].phi() << '\n';
  }
  if (png) writePng(grid, loop, *png);
  files.commit();
  log << path.size() << " scans along a loop of " << std::fixed << std::setprecision(1) << length << " m: "
      << std::setprecision(3) << length / double(path.size() - 1) << " m and at most " << std::setprecision(1)
      << mrpt::RAD2DEG(max_turn) << " deg a step; " << 100.0 * double(hits) / double(kBeams * path.size())
      << " % of the beams hit within " << kMaxRange << " m\n";
}

}  // namespace rtog::simlog
