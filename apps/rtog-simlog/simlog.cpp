// rtog-simlog's run: the map read, the loop driven, each step's odometry and laser scan
// simulated and written. Every random number comes from one generator seeded by --seed, drawn in
// a fixed order, so a seed always gives the same bytes.
#include <algorithm>
#include <cmath>
#include <iomanip>
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
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rtog/app/output_files.hpp"
#include "simlog.hpp"

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

CPose2D noisyOdometry(const CPose2D& moved, mrpt::random::CRandomGenerator& rng) {
  const double d = std::hypot(moved.x(), moved.y());
  const double k = 1.0 + kDistanceBias + kDistanceStd * rng.drawGaussian1D_normalized();
  const double lateral = kLateralStd * d * rng.drawGaussian1D_normalized();
  const double turn = moved.phi() * (1.0 + kTurnBias + kTurnStd * rng.drawGaussian1D_normalized()) +
                      kTurnPerMetreStd * d * rng.drawGaussian1D_normalized();
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
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", img, bytes)) throw std::runtime_error("cannot encode the --png image");
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
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
  const std::vector<TPoint2D> loop = planLoop(world, o.loop, log);
  const std::vector<CPose2D> path = poses(loop, o.scans);

  mrpt::random::CRandomGenerator rng(o.seed);
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;  // MRPT's Gaussian model
  motion.gaussianModel.a1 = kDistanceBias + kDistanceStd;
  motion.gaussianModel.a4 = kTurnBias + kTurnStd;
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
    move.computeFromOdometry(i == 0 ? CPose2D() : noisyOdometry(moved, rng), motion);
    mrpt::obs::CActionCollection actions;
    actions.insert(move);

    auto scan = mrpt::obs::CObservation2DRangeScan::Create();
    scan->sensorLabel = "LASER";
    scan->timestamp = t;
    scan->aperture = float(M_PI);
    scan->rightToLeft = true;
    scan->maxRange = kMaxRange;
    scan->stdError = float(kRangeStd);
    world.laserScanSimulator(*scan, path[i], 0.6f, kBeams);
    for (std::size_t b = 0; b < kBeams; ++b) {
      if (!scan->getScanRangeValidity(b)) continue;
      ++hits;
      const double r = scan->getScanRange(b) + kRangeStd * rng.drawGaussian1D_normalized();
      scan->setScanRange(b, float(std::clamp(r, 0.0, double(kMaxRange))));
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
