// `rtog build` on rawlogs of a few hundred bytes whose scans reach kilometres: the default range
// cut and the per-scan cell budget keep the tool's memory bounded, and the summary counts what
// they cut or skipped.
#include <gtest/gtest.h>

#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/serialization/CArchive.h>

#include "cli_helpers.hpp"

using namespace rtog_cli_test;

namespace {

/// A rawlog (observations only, uncompressed) of `scans` 2D scans of 361 beams over 180 degrees,
/// every beam reading `range` metres, the sensor's own maxRange just beyond it.
std::string farScans(const std::string& path, int scans, float range) {
  mrpt::io::CFileOutputStream f(path);
  auto ar = mrpt::serialization::archiveFrom(f);
  for (int s = 0; s < scans; ++s) {
    mrpt::obs::CObservation2DRangeScan obs;
    obs.aperture = static_cast<float>(M_PI);
    obs.maxRange = range + 1.0f;
    obs.sensorLabel = "LASER";
    obs.resizeScanAndAssign(361, range, true);
    ar << obs;
  }
  f.close();
  return path;
}

}  // namespace

// One scan of 361 beams at 3,276 m, each within the 65,536-cell bound of a beam: the default
// --max-range (120 m) cuts them (before: no cut, 3.2 GB and an 842 MB map). Counted in the summary.
TEST(CliScanBudget, AFarScanIsCutByTheDefaultRange) {
  const std::string d = scratch("far_scan");
  const std::string log = farScans(d + "/far.rawlog", 1, 3276.0f);
  const Child c = spawn({"build", "--rawlog", log, "--out", d + "/m.rtog"});
  std::cout << "peak memory " << c.maxrss_kb / 1024 << " MiB, map " << readAll(d + "/m.rtog").size() << " bytes\n";
  EXPECT_EQ(c.rc, 0) << c.output;
  EXPECT_NE(c.output.find("361 cut at the range limit"), std::string::npos) << c.output;
  EXPECT_LT(c.maxrss_kb, 400 * 1024) << "peak memory " << c.maxrss_kb / 1024 << " MiB";
  EXPECT_LT(readAll(d + "/m.rtog").size(), 64u << 20);  // before: 842 MB
}

// With no range cut (--max-range 0) the per-scan cell budget skips such scans whole and counts
// their beams (before: 3.2 GB, as with one: the second scan touches the same cells).
TEST(CliScanBudget, WithNoRangeCutTheCellBudgetSkipsTheScans) {
  const std::string d = scratch("far_scans");
  const std::string log = farScans(d + "/far.rawlog", 2, 3276.0f);
  const Child c = spawn({"build", "--rawlog", log, "--max-range", "0", "--out", d + "/m.rtog"});
  std::cout << "peak memory " << c.maxrss_kb / 1024 << " MiB\n";
  EXPECT_EQ(c.rc, 0) << c.output;
  EXPECT_NE(c.output.find("722 in scans over the cell budget (1073741824 cells)"), std::string::npos) << c.output;
  // AddressSanitizer's shadow and quarantine add their own (752 MiB measured): the bound doubles.
#if defined(__SANITIZE_ADDRESS__)
  constexpr long kBoundMiB = 1200;
#else
  constexpr long kBoundMiB = 600;
#endif
  EXPECT_LT(c.maxrss_kb, kBoundMiB * 1024) << "peak memory " << c.maxrss_kb / 1024 << " MiB";
}

// The budget is an insertion option of the MRPT map (.ini key maxScanCells): a smaller one skips
// what the default would take, 0 lifts it.
TEST(CliScanBudget, TheBudgetIsAnIniOption) {
  const std::string d = scratch("budget_ini");
  const std::string log = farScans(d + "/near.rawlog", 1, 30.0f);
  for (const auto& [budget, skipped] : std::vector<std::pair<std::string, std::string>>{
           {"", "0 in scans over the cell budget (1073741824 cells)"},
           {"maxScanCells = 4096\n", "361 in scans over the cell budget (4096 cells)"},
           {"maxScanCells = 0\n", "0 in scans over the cell budget (0 cells)"}}) {
    writeAll(d + "/m.ini", "[map]\nrtreeOccupancyGrid_count = 1\n[map_rtreeOccupancyGrid_00_creationOpts]\nresolution = 0.05\n"
                          "[map_rtreeOccupancyGrid_00_insertOpts]\nsensorModelPreset = octomap\nmaxDistanceInsertion = 0\n" + budget);
    std::string out;
    EXPECT_EQ(run("build --rawlog " + log + " --ini " + d + "/m.ini --section map", &out), 0) << out;
    EXPECT_NE(out.find(skipped), std::string::npos) << budget << out;
  }
}
