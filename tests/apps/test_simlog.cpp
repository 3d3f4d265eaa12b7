// rtog-simlog as a process on Debian's Malaga campus gridmap: the rawlog MRPT reads back (pairs,
// labels, ranges, timestamps), every beam ending at the first wall seen from the ground truth,
// odometry close to the true motion but noisy, one seed one set of bytes, and bad input refused
// with one line.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include "cli_helpers.hpp"

namespace {

using rtog_cli_test::readAll;
using rtog_cli_test::scratch;
using rtog_cli_test::spawn;

const std::string kMalaga = std::string(RTOG_MRPT_DATASETS) + "/2006-MalagaCampus.gridmap.gz";
constexpr int kScans = 200;

struct Pose {
  double t, x, y, phi;
};

std::vector<Pose> readGt(const std::string& path) {
  std::vector<Pose> out;
  std::ifstream in(path);
  for (Pose p{}; in >> p.t >> p.x >> p.y >> p.phi;) out.push_back(p);
  return out;
}

// One run on the Malaga map, made once per process (the checks below share it).
struct Made {
  std::string dir, rawlog, gt;
  rtog_cli_test::Child run;
};
const Made& made() {
  static const Made m = [] {
    Made r;
    r.dir = scratch("simlog");
    r.rawlog = r.dir + "/a.rawlog", r.gt = r.dir + "/a.gt";
    r.run = spawn({kMalaga, r.rawlog, "--scans", std::to_string(kScans), "--seed", "7", "--gt", r.gt});
    return r;
  }();
  return m;
}

mrpt::maps::COccupancyGridMap2D malaga() {
  mrpt::maps::COccupancyGridMap2D g;
  mrpt::io::CFileGZInputStream f(kMalaga);
  mrpt::serialization::archiveFrom(f) >> g;
  return g;
}

TEST(Simlog, MrptReadsActionSensoryFramePairsOfValidScans) {
  const Made& m = made();
  ASSERT_EQ(m.run.rc, 0) << m.run.output;
  mrpt::obs::CRawlog log;
  ASSERT_TRUE(log.loadFromRawLogFile(m.rawlog));
  ASSERT_EQ(log.size(), 2u * kScans);
  mrpt::Clock::time_point last{};
  for (std::size_t i = 0; i < log.size(); i += 2) {
    ASSERT_EQ(log.getType(i), mrpt::obs::CRawlog::etActionCollection) << i;
    ASSERT_EQ(log.getType(i + 1), mrpt::obs::CRawlog::etSensoryFrame) << i;
    ASSERT_TRUE(log.getAsAction(i)->getBestMovementEstimation()) << i;
    const auto frame = log.getAsObservations(i + 1);
    ASSERT_EQ(frame->size(), 1u);
    const auto scan = frame->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    ASSERT_TRUE(scan) << i;
    EXPECT_EQ(scan->sensorLabel, "LASER");
    EXPECT_GT(scan->timestamp, last) << i;
    last = scan->timestamp;
    ASSERT_EQ(scan->getScanSize(), 361u);
    std::size_t valid = 0;
    for (std::size_t b = 0; b < scan->getScanSize(); ++b) {
      if (!scan->getScanRangeValidity(b)) continue;
      ++valid;
      EXPECT_TRUE(scan->getScanRange(b) > 0.0f && scan->getScanRange(b) <= scan->maxRange) << i << " " << b;
    }
    EXPECT_GT(valid, scan->getScanSize() / 2) << "scan " << i / 2 << " sees little";
  }
}

TEST(Simlog, GroundTruthIsInFreeSpaceAndOdometryNoisyButClose) {
  const Made& m = made();
  ASSERT_EQ(m.run.rc, 0) << m.run.output;
  const std::vector<Pose> gt = readGt(m.gt);
  ASSERT_EQ(gt.size(), std::size_t(kScans));
  EXPECT_NEAR(gt.front().x, gt.back().x, 1e-6) << "the loop ends where it started";
  EXPECT_NEAR(gt.front().y, gt.back().y, 1e-6);
  mrpt::obs::CRawlog log;
  ASSERT_TRUE(log.loadFromRawLogFile(m.rawlog));
  const mrpt::maps::COccupancyGridMap2D map = malaga();
  std::size_t odometry_differs = 0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const mrpt::poses::CPose2D pose(gt[i].x, gt[i].y, gt[i].phi);
    EXPECT_GT(map.getPos(gt[i].x, gt[i].y), 0.6f) << "pose " << i << " is not in the map's free space";
    const auto scan = log.getAsObservations(2 * i + 1)->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    EXPECT_NEAR(mrpt::Clock::toDouble(scan->timestamp), gt[i].t, 1e-3);
    if (i == 0) continue;
    const mrpt::poses::CPose2D moved = pose - mrpt::poses::CPose2D(gt[i - 1].x, gt[i - 1].y, gt[i - 1].phi);
    const auto move = log.getAsAction(2 * i)->getActionByClass<mrpt::obs::CActionRobotMovement2D>();
    ASSERT_TRUE(move) << i;
    const mrpt::poses::CPose2D odometry = move->rawOdometryIncrementReading;
    // Bounds of about five standard deviations of the noise rtog-simlog adds.
    EXPECT_NEAR(odometry.x(), moved.x(), 0.15 * moved.norm()) << i;
    EXPECT_NEAR(odometry.y(), moved.y(), 0.15 * moved.norm()) << i;
    EXPECT_NEAR(odometry.phi(), moved.phi(), 0.2 * std::abs(moved.phi()) + 0.1 * moved.norm()) << i;
    odometry_differs += std::abs(odometry.x() - moved.x()) > 1e-6;
  }
  EXPECT_GT(odometry_differs, gt.size() / 2) << "the odometry has no noise";
}

// Every beam ends where it meets the first cell the map does not know free (the tool's world:
// walls and unknown space are solid), seen from the ground-truth pose: up to a little short of
// its end the beam crosses free cells only, and around its end it meets a solid one. MRPT 2.5's
// laserScanSimulator fails this (a sixth of the beams pass through a wall): it steps along a
// direction rounded to 1/1024 of a step, so each beam leans by up to a quarter degree.
TEST(Simlog, EveryBeamEndsAtTheFirstWallSeenFromTheGroundTruth) {
  const Made& m = made();
  ASSERT_EQ(m.run.rc, 0) << m.run.output;
  const std::vector<Pose> gt = readGt(m.gt);
  mrpt::obs::CRawlog log;
  ASSERT_TRUE(log.loadFromRawLogFile(m.rawlog));
  ASSERT_EQ(log.size(), 2 * gt.size());
  const mrpt::maps::COccupancyGridMap2D map = malaga();
  auto free_at = [&](const Pose& p, double angle, double range) {
    const int cx = map.x2idx(p.x + range * std::cos(angle)), cy = map.y2idx(p.y + range * std::sin(angle));
    return cx >= 0 && cy >= 0 && cx < int(map.getSizeX()) && cy < int(map.getSizeY()) && map.getCell(cx, cy) > 0.6f;
  };
  const double margin = 0.06;  // six standard deviations of the range noise
  std::size_t beams = 0, through_wall = 0, in_free_space = 0;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const auto scan = log.getAsObservations(2 * i + 1)->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    const std::size_t n = scan->getScanSize();
    for (std::size_t b = 0; b < n; ++b) {
      if (!scan->getScanRangeValidity(b)) continue;
      ++beams;
      const double a = gt[i].phi - scan->aperture / 2 + scan->aperture * double(b) / double(n - 1);
      const double r = scan->getScanRange(b);
      bool crossed_solid = false, met_solid = false;
      for (double t = 0; t < r - margin && !crossed_solid; t += 0.02) crossed_solid = !free_at(gt[i], a, t);
      for (double t = r - margin; t <= r + margin && !met_solid; t += 0.005) met_solid = !free_at(gt[i], a, t);
      through_wall += crossed_solid;
      in_free_space += !met_solid;
    }
  }
  // A beam grazing a corner or along a wall may meet it a hair off the line sampled here (the
  // ground truth is written to a micrometre): one in a hundred is allowed.
  EXPECT_LT(through_wall, beams / 100) << "of " << beams << " beams, " << through_wall << " pass through a wall";
  EXPECT_LT(in_free_space, beams / 100) << "of " << beams << " beams, " << in_free_space << " end in free space";
}

TEST(Simlog, OneSeedGivesTheSameBytesAnotherSeedOtherNoiseOnTheSamePath) {
  const Made& m = made();
  ASSERT_EQ(m.run.rc, 0) << m.run.output;
  const std::string same = m.dir + "/same.rawlog", other = m.dir + "/other.rawlog";
  ASSERT_EQ(spawn({kMalaga, same, "--scans", std::to_string(kScans), "--seed", "7", "--gt", same + ".gt"}).rc, 0);
  ASSERT_EQ(spawn({kMalaga, other, "--scans", std::to_string(kScans), "--seed", "8", "--gt", other + ".gt"}).rc, 0);
  EXPECT_TRUE(readAll(same) == readAll(m.rawlog)) << "seed 7 twice gave different rawlogs";
  EXPECT_EQ(readAll(same + ".gt"), readAll(m.gt));
  EXPECT_FALSE(readAll(other) == readAll(m.rawlog)) << "seeds 7 and 8 gave the same rawlog";
  EXPECT_EQ(readAll(other + ".gt"), readAll(m.gt)) << "the ground truth depends on the map only";
}

// Twice the area the path encloses, positive if it turns counterclockwise (shoelace).
double signedArea2(const std::vector<Pose>& path) {
  double a = 0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Pose& p = path[i];
    const Pose& q = path[(i + 1) % path.size()];
    a += p.x * q.y - q.x * p.y;
  }
  return a;
}

TEST(Simlog, ReverseDrivesTheSameLoopTheOtherWayRound) {
  const Made& m = made();
  ASSERT_EQ(m.run.rc, 0) << m.run.output;
  const std::string back = m.dir + "/back.rawlog";
  ASSERT_EQ(spawn({kMalaga, back, "--scans", std::to_string(kScans), "--reverse", "--gt", back + ".gt"}).rc, 0);
  const double forward = signedArea2(readGt(m.gt)), reverse = signedArea2(readGt(back + ".gt"));
  EXPECT_LT(forward * reverse, 0) << "both ways turn the same way";
  EXPECT_NEAR(std::abs(reverse), std::abs(forward), 0.05 * std::abs(forward)) << "not the same loop";
}

// A one-line message naming the problem, a non-zero exit, and no output file left.
void expectRefused(const std::vector<std::string>& args, int rc, const std::string& message, const std::string& out) {
  const rtog_cli_test::Child c = spawn(args);
  EXPECT_EQ(c.rc, rc) << c.output;
  EXPECT_NE(c.output.find(message), std::string::npos) << c.output;
  EXPECT_EQ(std::count(c.output.begin(), c.output.end(), '\n'), 1) << c.output;
  EXPECT_FALSE(std::ifstream(out).good()) << out << " was written";
}

TEST(Simlog, BadInputIsRefusedWithOneLine) {
  const std::string d = scratch("simlog_bad");
  const std::string out = d + "/out.rawlog";
  expectRefused({d + "/missing.gridmap", out}, 1, "cannot open gridmap " + d + "/missing.gridmap", out);
  rtog_cli_test::writeAll(d + "/junk.gridmap", std::string(4096, 'x'));
  expectRefused({d + "/junk.gridmap", out}, 1, "junk.gridmap is not a gridmap", out);
  // The start of a real gridmap, cut off.
  rtog_cli_test::writeAll(d + "/cut.gridmap", readAll(kMalaga).substr(0, 20000));
  expectRefused({d + "/cut.gridmap", out}, 1, "cut.gridmap is not a gridmap", out);
  expectRefused({kMalaga, out, "--scans", "0"}, 2, "--scans", out);
  expectRefused({kMalaga, out, "--scans", "-5"}, 2, "--scans", out);
  expectRefused({kMalaga, kMalaga}, 1, "rawlog", kMalaga + ".none");

  // A map with free space but nothing to drive around.
  mrpt::maps::COccupancyGridMap2D open(-10, 10, -10, 10, 0.1f);
  open.fill(0.9f);
  {
    mrpt::io::CFileGZOutputStream f(d + "/open.gridmap.gz");
    mrpt::serialization::archiveFrom(f) << open;
  }
  expectRefused({d + "/open.gridmap.gz", out}, 1, "no closed loop in the map", out);
}

}  // namespace
