// Errors a person reads (issue #37): a bad .ini value, an MRPT exception, an option that cannot
// be represented or would have no effect, each told by the tool as a process in one line that
// names what to fix, with the CLI's exit codes (2: the command line, 1: an input).
#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>

#include "../mrpt/hostile_files.hpp"
#include "cli_helpers.hpp"
#include "commands.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

using namespace rtog_cli_test;

namespace {

const std::string kTum = std::string(" --tum ") + RTOG_TEST_TUM_DIR + " --stride 16 ";

/// Runs `rtog <args>` (a generous timeout: a hang is a failure, not a stuck test) and expects
/// exit code `rc` and exactly one line of output, "rtog: error: ...", holding each of `words`,
/// with nothing of MRPT's multi-line exceptions.
void expectOneLine(const std::string& args, int rc, std::initializer_list<std::string> words) {
  std::string out;
  EXPECT_EQ(run(args, &out, "timeout 120 "), rc) << args << "\n" << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << "\n" << out;
  EXPECT_EQ(out.rfind("rtog: error: ", 0), 0u) << args << "\n" << out;
  EXPECT_EQ(out.find("Call stack"), std::string::npos) << args << "\n" << out;
  EXPECT_EQ(out.find("MRPT exception"), std::string::npos) << args << "\n" << out;
  for (const std::string& w : words) EXPECT_NE(out.find(w), std::string::npos) << args << ": wants '" << w << "'\n" << out;
}

std::string iniWith(const std::string& dir, const std::string& name, const std::string& body) {
  const std::string path = dir + "/" + name;
  writeAll(path, "[MappingApplication]\nrtreeOccupancyGrid_count=1\n" + body);
  return path;
}

}  // namespace

// A bad value in an .ini reached the user as MRPT's exception: a header, the message cut at its
// first ']' (the section's name split in two), a location and a call stack of addresses.
TEST(CliErrors, BadIniValuesAreOneLineNamingSectionAndKey) {
  const std::string d = scratch("ini_errors");
  const std::string creation = "[MappingApplication_rtreeOccupancyGrid_00_creationOpts]\n";
  const std::string insert = "[MappingApplication_rtreeOccupancyGrid_00_insertOpts]\n";
  expectOneLine("build" + kTum + "--ini " + iniWith(d, "neg.ini", creation + "resolution=-1\n"), 1,
                {"[MappingApplication_rtreeOccupancyGrid_00_creationOpts] resolution: must lie in [1e-4, 1e3] m"});
  expectOneLine("build" + kTum + "--ini " + iniWith(d, "abc.ini", creation + "resolution=0.1abc\n"), 1,
                {"[MappingApplication_rtreeOccupancyGrid_00_creationOpts] resolution: must be a number"});
  expectOneLine("build" + kTum + "--ini " + iniWith(d, "bool.ini", insert + "discretize = maybe\n"), 1,
                {"[MappingApplication_rtreeOccupancyGrid_00_insertOpts] discretize: must be a boolean"});
  expectOneLine("build" + kTum + "--ini " + iniWith(d, "model.ini", insert + "sensorModel = laser\n"), 1,
                {"sensor model"});
  // MRPT's own exception (its gas grid needs keys it finds missing): its message, no more.
  writeAll(d + "/gas.ini", "[MappingApplication]\ngasGrid_count=1\nrtreeOccupancyGrid_count=1\n");
  expectOneLine("build" + kTum + "--ini " + d + "/gas.ini", 1,
                {"Value 'gasSensorLabel' not found in section 'MappingApplication_gasGrid_00_insertOpts'"});
}

// Every command that reads through MRPT tells its exceptions in one line: a map whose archive
// names an unknown class (info, export, fuse, plan, image), a .gridmap that is none (prior).
TEST(CliErrors, EveryCommandTellsMrptErrorsInOneLine) {
  const std::string d = scratch("mrpt_errors");
  rtog::CRTreeOccupancyGridMap m(0.2);
  m.map() = rtog::cli::loadMap(smallMap());
  std::string archive = rtog_test::archiveBytes(m);
  archive[archive.find("CRTreeOccupancyGridMap") + 21] = 'q';
  const std::string bad = d + "/bad.rtog";
  writeAll(bad, rtog_test::gzip(archive));
  const std::string why = "Stored object has class 'rtog::CRTreeOccupancyGridMaq' which is not registered!";
  expectOneLine("info " + bad, 1, {why});
  expectOneLine("export " + bad + " --ply " + d + "/x.ply", 1, {why});
  expectOneLine("fuse " + smallMap() + " " + bad + " --out " + d + "/f.rtog", 1, {why});
  expectOneLine("plan " + bad + " --from 0 0 --to 1 1 --Te 1 --Ta 1 --out " + d + "/p.txt", 1, {why});
  expectOneLine("image " + bad + " --out " + d + "/i.json", 1, {why});
  writeAll(d + "/bad.gridmap.gz", rtog_test::gzip("no grid map"));
  expectOneLine("prior --gridmap " + d + "/bad.gridmap.gz --out " + d + "/p.rtog", 1, {"bad.gridmap.gz"});
}

// Map options beside --ini had no effect, without a word (the .ini defines the map); --stride
// without --tum neither. Each is a usage error naming the option and where to set it instead.
TEST(CliErrors, OptionsWithoutEffectAreRefused) {
  const std::string ini = std::string(RTOG_SOURCE_DIR) + "/share/rtog/config/rtog_build.ini";
  expectOneLine("build" + kTum + "--ini " + ini + " --resolution 0.2", 2,
                {"--resolution has no effect with --ini", "set resolution in its _creationOpts"});
  expectOneLine("build" + kTum + "--ini " + ini + " --threads 2", 2, {"--threads has no effect with --ini", "threads"});
  expectOneLine("build" + kTum + "--ini " + ini + " --discretize", 2, {"--discretize has no effect with --ini"});
  expectOneLine("build" + kTum + "--ini " + ini + " --model endpoint", 2, {"--model", "sensorModel"});
  expectOneLine("build" + kTum + "--ini " + ini + " --miss-rate 0.1 --false-alarm-rate 0.1", 2, {"missRate"});
  expectOneLine("build" + kTum + "--ini " + ini + " --range-noise-shared-band 8", 2,
                {"--range-noise-shared-band has no effect with --ini", "rangeNoiseSharedBand"});
  const std::string log = std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
  expectOneLine("build --rawlog '" + log + "' --stride 4", 2, {"--stride has no effect without --tum"});
  expectOneLine("image " + smallMap() + " --out /dev/null --hough-min-length 2", 2, {"--hough-min-length requires --hough"});
}

// Numbers the tool turns into whole cells or pixels wrapped: --hough-min-length 1e9 found walls
// as if it were tiny, --hough-max-gap 1e9 as 0, --blur 1e8 failed inside OpenCV, --pose 1e20
// made fuse loop for ever. Each such option has a stated range, refused by name (exit 2; the
// pose by the fuse command, exit 1, as its other bad values).
TEST(CliErrors, NumbersBeyondAnOptionsRangeAreRefused) {
  const std::string d = scratch("ranges");
  const std::string map = smallMap(), img = "image " + map + " --out " + d + "/i.json ";
  expectOneLine(img + "--hough --hough-min-length 1e9", 2, {"--hough-min-length: must be at most 10000, got 1e9"});
  expectOneLine(img + "--hough --hough-max-gap 1e9", 2, {"--hough-max-gap: must be at most 10000"});
  expectOneLine(img + "--blur 1e8", 2, {"--blur: must be at most 10000"});
  const std::string plan = "plan " + map + " --Te 1 --Ta 1 --out " + d + "/p.txt ";
  expectOneLine(plan + "--from 0 0 --to 0 5 --radius 1e300", 2, {"--radius: must be at most 10000"});
  expectOneLine(plan + "--from 0 0 --to 0 5 --unknown-cost nan", 2, {"--unknown-cost: must be a finite number"});
  writeAll(d + "/b.rtog", readAll(map));
  // The pose's values are the fuse command's to check (exit 1, as for a NaN pose).
  expectOneLine("fuse " + map + " " + d + "/b.rtog --out " + d + "/f.rtog --pose 1e20 0 0 0 0 0", 1,
                {"--pose: x y z must lie within +-1e9 m"});
  expectOneLine("build" + kTum + "--resolution 1e300", 2, {"--resolution: must be at most 1000"});
  expectOneLine("build" + kTum + "--resolution 0.2 --max-range 1e300", 2, {"--max-range: must be at most 1000000"});
  expectOneLine("build" + kTum + "--resolution 0.2 --miss-rate 1e300 --false-alarm-rate 0.1", 2,
                {"--miss-rate: must be at most 1"});
  expectOneLine("build" + kTum + "--resolution 0.2 --model rangeNoise --range-noise-cutoff nan", 2,
                {"--range-noise-cutoff: must be a finite number"});
  expectOneLine("prior --gridmap " + std::string(RTOG_MRPT_DATASETS) + "/2006-MalagaCampus.gridmap.gz --confidence nan --out " +
                    d + "/p.rtog", 2, {"--confidence: must be a finite number"});
  // At the bounds, the options still work.
  std::string out;
  EXPECT_EQ(run(img + "--hough --hough-min-length 10000 --hough-max-gap 10000 --blur 0.3", &out), 0) << out;
}
