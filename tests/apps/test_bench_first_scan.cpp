// The bench's first-scan rows on a tiny real input (SENA's first 2D laser scan, 361 beams): every
// map type's row is there with sane figures, each sample from a process of its own, the rows
// survive the JSON and reach the report's targets. Also the TUM frame the rows insert, as an
// MRPT observation, against the bench's own reading of it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservation3DRangeScan.h>

#include "first_scan.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/image/tum_dataset.hpp"

using namespace rtog::bench;

namespace {

const std::string kSena = std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
const FirstScanSource kSenaSource{"rawlog2d", kSena, "SENA 2D laser, first scan"};

std::vector<Result> senaRows(int repeats) {
  Options opts;
  opts.repeats = repeats;
  opts.resolutions = {0.1};
  std::vector<Result> rows;
  std::ostringstream log;
  runFirstScans(RTOG_FIRST_SCAN_EXE, {kSenaSource}, opts, rows, log);
  return rows;
}

TEST(BenchFirstScan, EveryMapTypeHasASaneRow) {
  const std::vector<Result> rows = senaRows(3);
  ASSERT_EQ(rows.size(), 3u);  // rtreeOccupancyGrid, octoMap, occupancyGrid
  for (const Result& r : rows) {
    SCOPED_TRACE(r.method);
    EXPECT_EQ(r.method.rfind("first scan: ", 0), 0u);
    EXPECT_NE(r.method.find(", from CObservation2DRangeScan"), std::string::npos);
    EXPECT_EQ(r.extra.at("as_recorded"), 0.0);
    EXPECT_EQ(r.dataset, kSenaSource.label);
    EXPECT_EQ(r.resolution, 0.1);
    EXPECT_EQ(r.extra.at("first_scan"), 1.0);
    EXPECT_EQ(r.extra.at("repeats"), 3.0);
    ASSERT_EQ(r.build_seconds.size(), 3u);  // one per process
    for (const double s : r.build_seconds) EXPECT_GT(s, 0.0);
    EXPECT_GT(r.insert_seconds, 0.0);
    EXPECT_LT(r.insert_seconds, 10.0);
    EXPECT_EQ(r.extra.at("points"), 361.0);  // SENA's scans have 361 beams
    EXPECT_GT(r.structure_bytes, 0u);
    EXPECT_GE(r.extra.at("create_seconds"), 0.0);
    // Held memory includes the map's own except what it had before the scan, and stays far below
    // what a leak of the whole rawlog would be (169 kB on disk).
    EXPECT_TRUE(std::isfinite(r.extra.at("heap_held_bytes")));
    EXPECT_GE(r.extra.at("heap_held_bytes"), r.extra.at("heap_held_uordblks_bytes") - 1.0);
    EXPECT_LT(r.extra.at("heap_held_bytes"), 64.0 * 1048576.0);
  }
#ifndef RTOG_SANITIZED  // a sanitizer's allocator is not glibc's: mallinfo2 does not see it
  // The rtog and OctoMap maps start empty: the scan's cells are all held after it.
  for (const Result& r : rows) {
    if (r.method.find("COccupancyGridMap2D") == std::string::npos) {
      EXPECT_GE(r.extra.at("heap_held_bytes"), 0.5 * double(r.structure_bytes)) << r.method;
    }
  }
#endif
}

TEST(BenchFirstScan, RowsSurviveTheJsonAndReachTheTargets) {
  const std::vector<Result> rows = senaRows(1);
  RunInfo run;
  run.machine = machineFacts();
  const std::string json = ::testing::TempDir() + "/first_scan_" + std::to_string(getpid()) + ".json";
  const std::string md = ::testing::TempDir() + "/first_scan_" + std::to_string(getpid()) + ".md";
  {
    rtog::app::OutputSet files;
    writeJson(rows, run, files.add("--json", json));
    writeMarkdown(rows, run, files.add("--markdown", md), ::testing::TempDir(), files);
    files.commit();
  }
  RunInfo again;
  const std::vector<Result> back = readJson(json, again);
  ASSERT_EQ(back.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(back[i].method, rows[i].method);
    EXPECT_EQ(back[i].extra, rows[i].extra);
    EXPECT_EQ(back[i].structure_bytes, rows[i].structure_bytes);
  }
  std::ifstream in(md);
  int speed = 0, heap = 0, table = 0;
  for (std::string line; std::getline(in, line);) {
    const bool verdict = line.find("| PASS |") != std::string::npos || line.find("| FAIL |") != std::string::npos;
    if (line.find("first scan, fresh process") != std::string::npos) speed += verdict;
    if (line.find("heap held after the first scan") != std::string::npos) heap += verdict;
    if (line.rfind("| " + kSenaSource.label + " | 0.1 | ", 0) == 0 && !verdict) ++table;
  }
  EXPECT_EQ(speed, 1);
  EXPECT_EQ(heap, 1);
  EXPECT_EQ(table, 3);
}

TEST(BenchFirstScan, HelperRefusesABadCommandLine) {
  FirstScanSource missing = kSenaSource;
  missing.path = ::testing::TempDir() + "/no_such.rawlog";
  EXPECT_THROW(runFirstScanProcess(RTOG_FIRST_SCAN_EXE, missing, {"octoMap"}, 0.1), std::runtime_error);
  EXPECT_THROW(runFirstScanProcess(RTOG_FIRST_SCAN_EXE, kSenaSource, {"noSuchMap"}, 0.1), std::runtime_error);
  // CLI11's own number checks let "nan" through (NaN compares false): a NaN cell size is refused.
  EXPECT_THROW(runFirstScanProcess(RTOG_FIRST_SCAN_EXE, kSenaSource, {"octoMap"}, std::nan("")), std::runtime_error);
}

TEST(BenchCli, NonFiniteValuesAreRefusedWithAMessage) {
  for (const std::string args : {"--resolutions nan", "--resolutions 0.1 inf", "--resolutions -0.1", "--min-seconds nan"}) {
    const std::string cmd = std::string(RTOG_BENCH_EXE) + " --only tum --methods none " + args + " --json " +
                            ::testing::TempDir() + "/bench_cli.json --markdown " + ::testing::TempDir() +
                            "/bench_cli.md 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    std::string out;
    char buf[512];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    const int status = pclose(p);
    EXPECT_NE(status, 0) << args << ": " << out;
    EXPECT_NE(out.find("must be"), std::string::npos) << args << ": " << out;
  }
}

// The TUM frame the first-scan rows insert: through MRPT's own unprojection (as COctoMap and
// every MRPT map see it) the same world points as the bench's reading of the frame.
TEST(BenchFirstScan, TumFrameAsAnMrptObservationHasTheBenchPoints) {
  const rtog::image::DepthSequence seq = rtog::image::readTumSequence(RTOG_TEST_TUM_DIR);
  ASSERT_FALSE(seq.frames.empty());
  const auto obs = tumDepthObservation(seq.frames.front(), seq.intrinsics);
  mrpt::maps::CSimplePointsMap pm;
  mrpt::obs::T3DPointsProjectionParams pp;
  pp.takeIntoAccountSensorPoseOnRobot = true;  // the robot is at the origin: world coordinates
  obs->unprojectInto(pm, pp);
  const rtog::image::WorldScan scan = rtog::image::loadDepthScan(seq.frames.front(), seq.intrinsics);
  ASSERT_EQ(pm.size(), scan.points.size());
  ASSERT_GT(pm.size(), 100000u);
  double worst = 0;
  for (std::size_t i = 0; i < pm.size(); i += 97) {
    float x, y, z;
    pm.getPoint(i, x, y, z);
    worst = std::max(worst, double((Eigen::Vector3f(x, y, z) - scan.points[i]).norm()));
  }
  EXPECT_LT(worst, 1e-3);
  mrpt::poses::CPose3D sensor;
  obs->getSensorPose(sensor);
  EXPECT_NEAR((Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z()) - scan.origin).norm(), 0.0, 1e-9);
}

}  // namespace
