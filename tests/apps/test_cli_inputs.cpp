// What rtog reads, as a hostile user would feed it: maps through pipes, bytes after a map,
// length fields that promise a terabyte, numbers that are not numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include "../mrpt/hostile_files.hpp"
#include "cli_helpers.hpp"
#include "commands.hpp"
#include "rtog/core/mesh_export.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

using namespace rtog_cli_test;

namespace {

/// The small map as the MRPT map type saves it (gzip CArchive), the format MRPT's apps write.
std::string mrptFormatCopy(const std::string& dir) {
  rtog::CRTreeOccupancyGridMap m(0.2);
  m.map() = rtog::cli::loadMap(smallMap());
  const std::string path = dir + "/m.gz";
  m.saveToFile(path);
  return path;
}

/// `info --json` without the memory figure, which depends on how the leaves were allocated.
std::string withoutMemory(const std::string& json) {
  std::istringstream in(json);
  std::string line, out;
  while (std::getline(in, line))
    if (line.find("\"memory_bytes\"") == std::string::npos) out += line + "\n";
  return out;
}

std::string plyOf(const std::string& map) {
  std::ostringstream os;
  rtog::writeOccupiedPly(rtog::cli::loadMap(map), os);
  return os.str();
}

TEST(CliInputs, MapsReadFromAPipe) {
  const std::string d = scratch("pipe_in");
  const std::string gz = mrptFormatCopy(d);
  std::string want, out;
  ASSERT_EQ(run("info --json " + smallMap(), &want), 0) << want;
  EXPECT_EQ(run("info --json /dev/stdin", &out, "cat '" + smallMap() + "' | "), 0) << out;
  EXPECT_EQ(out, want);
  EXPECT_EQ(run("info --json /dev/stdin", &out, "cat '" + gz + "' | "), 0) << out;
  EXPECT_EQ(withoutMemory(out), withoutMemory(want));
  EXPECT_EQ(run("export /dev/stdin --ply " + d + "/x.ply", &out, "cat '" + smallMap() + "' | "), 0) << out;
  EXPECT_TRUE(readAll(d + "/x.ply") == plyOf(smallMap()));
}

TEST(CliInputs, TrailingBytesAfterAMapAreAnError) {
  const std::string d = scratch("trailing");
  const std::string gz = mrptFormatCopy(d);
  writeAll(d + "/core.rtog", readAll(smallMap()) + "junk!");
  writeAll(d + "/gz_after.rtog", readAll(gz) + "junk");
  rtog::CRTreeOccupancyGridMap m(0.2);
  m.map() = rtog::cli::loadMap(smallMap());
  writeAll(d + "/gz_inside.rtog", rtog_test::gzip(rtog_test::archiveBytes(m) + "xyz"));
  std::string out;
  for (const auto& [file, n] : std::vector<std::pair<std::string, std::string>>{
           {"core.rtog", "5 trailing bytes"}, {"gz_after.rtog", "4 trailing bytes"}, {"gz_inside.rtog", "3 trailing bytes"}}) {
    EXPECT_EQ(run("info " + d + "/" + file, &out), 1) << file << ": " << out;
    EXPECT_NE(out.find(n + " after the map"), std::string::npos) << file << ": " << out;
  }
  // A damaged archive inside a good gzip stream: MRPT's exceptions told in one line.
  const std::string archive = rtog_test::archiveBytes(m);
  writeAll(d + "/gz_cut.rtog", rtog_test::gzip(archive.substr(0, 100)));
  std::string renamed = archive;
  renamed[renamed.find("CRTreeOccupancyGridMap") + 21] = 'q';
  writeAll(d + "/gz_class.rtog", rtog_test::gzip(renamed));
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"gz_cut.rtog", "truncated stream (the archive ends early)"},
           {"gz_class.rtog", "Stored object has class 'rtog::CRTreeOccupancyGridMaq' which is not registered!"}}) {
    EXPECT_EQ(run("info " + d + "/" + file, &out), 1) << file << ": " << out;
    EXPECT_EQ(out, "rtog: error: '" + d + "/" + file + "': " + message + "\n");
  }
  // Missing bytes, no bytes, a directory: each its own reason.
  const std::string whole = readAll(smallMap());
  writeAll(d + "/cut.rtog", whole.substr(0, whole.size() / 2));
  EXPECT_EQ(run("info " + d + "/cut.rtog", &out), 1);
  EXPECT_NE(out.find("truncated"), std::string::npos) << out;
  writeAll(d + "/empty.rtog", "");
  EXPECT_EQ(run("info " + d + "/empty.rtog", &out), 1);
  EXPECT_NE(out.find("the file is empty"), std::string::npos) << out;
  EXPECT_EQ(run("info " + d, &out), 1);
  EXPECT_NE(out.find("is a directory"), std::string::npos) << out;
}

// A 64-bit length that says 2^40 and a string that says 1 GiB, in files of a few hundred bytes:
// a clear error, and no allocation of what they promise.
TEST(CliInputs, LengthFieldsCannotExhaustMemory) {
  const std::string d = scratch("huge_length");
  writeAll(d + "/block.rtog", rtog_test::hugeBlockFile(std::uint64_t{1} << 40));
  writeAll(d + "/string.rtog", rtog_test::hugeStringFile(1u << 30));
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"block.rtog", "truncated stream (map block: 1099511627776 bytes announced"},
           {"string.rtog", "corrupt stream (sensorModel: a 1073741824-byte string"}}) {
    const std::string path = d + "/" + file;
    std::cout << file << ": " << readAll(path).size() << " bytes\n";
    EXPECT_LT(readAll(path).size(), 400u);
    const Child c = spawn({"info", path});
    EXPECT_EQ(c.rc, 1) << c.output;
    EXPECT_NE(c.output.find(message), std::string::npos) << c.output;
    EXPECT_LT(c.maxrss_kb, 200 * 1024) << file << ": peak memory " << c.maxrss_kb / 1024 << " MiB";
  }
}

// One check for every number of every subcommand: finite, of the right sign, named in the error.
TEST(CliInputs, NumericOptionsMustBeFiniteNumbers) {
  const std::string tum = std::string("build --tum ") + RTOG_TEST_TUM_DIR + " ";
  const std::string fast = "--stride 16 ", coarse = "--resolution 0.2 ";
  std::string out;
  const auto refused = [&](const std::string& args, const std::string& message) {
    EXPECT_EQ(run(args, &out), 2) << args << ": " << out;
    EXPECT_NE(out.find(message), std::string::npos) << args << ": " << out;
  };
  for (const std::string v : {"nan", "inf", "-inf", "NaN"}) {
    refused(tum + fast + coarse + "--max-range " + v, "--max-range: must be a finite number");
    refused(tum + fast + "--resolution " + v, "--resolution: must be a finite number");
    refused("export " + smallMap() + " --png /dev/null --slice-z " + v, "--slice-z: must be a finite number");
  }
  refused(tum + fast + coarse + "--max-range -1", "--max-range: must be >= 0");
  refused(tum + fast + coarse + "--max-range 10m", "--max-range: '10m' is not a number");
  refused(tum + fast + "--resolution 0", "--resolution: must be > 0");
  refused(tum + fast + "--resolution -0.1", "--resolution: must be > 0");
  refused(tum + coarse + "--stride 0", "--stride: must lie in [1, 65536]");
  refused(tum + coarse + "--stride 1.5", "--stride: '1.5' is not a whole number");
  refused(tum + fast + coarse + "--threads 0", "--threads: must lie in [1, 256]");
  // 0 is the explicit "no cut"; a good value still works.
  EXPECT_EQ(run(tum + fast + coarse + "--max-range 0", &out), 0) << out;
  EXPECT_EQ(run(tum + fast + coarse + "--max-range 3.5", &out), 0) << out;
}

// The sensor stated as a miss / false-alarm channel: both rates or neither, finite, a channel
// that speaks for occupied; rates equivalent to the default probabilities build the same map.
TEST(CliInputs, MissAndFalseAlarmRatesStateTheSensor) {
  const std::string tum = std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --stride 16 --resolution 0.2 ";
  std::string out;
  EXPECT_EQ(run(tum + "--miss-rate 0.1", &out), 2) << out;
  EXPECT_NE(out.find("--false-alarm-rate"), std::string::npos) << out;
  EXPECT_EQ(run(tum + "--miss-rate nan --false-alarm-rate 0.1", &out), 2) << out;
  EXPECT_NE(out.find("--miss-rate: must be a finite number"), std::string::npos) << out;
  EXPECT_EQ(run(tum + "--miss-rate 0.6 --false-alarm-rate 0.5", &out), 1) << out;
  EXPECT_NE(out.find("below 1"), std::string::npos) << out;
  const std::string dir = scratch("channel"), plain = dir + "/plain.rtog", channel = dir + "/channel.rtog";
  ASSERT_EQ(run(tum + "--out " + plain, &out), 0) << out;
  ASSERT_EQ(run(tum + "--miss-rate 0.53333333333333333 --false-alarm-rate 0.2 --out " + channel, &out), 0) << out;
  EXPECT_EQ(plyOf(channel), plyOf(plain));
  EXPECT_GT(plyOf(plain).size(), 10000u);
  // A surer sensor: fewer beams make a cell occupied, so the map differs.
  ASSERT_EQ(run(tum + "--miss-rate 0.05 --false-alarm-rate 0.05 --out " + channel, &out), 0) << out;
  EXPECT_NE(plyOf(channel), plyOf(plain));
}

}  // namespace

namespace {

double entropyOf(const std::string& map) {
  std::string out;
  EXPECT_EQ(run("info --json " + map, &out), 0) << out;
  const auto at = out.find("\"mean_entropy_bits\": ");
  return at == std::string::npos ? -1.0 : std::stod(out.substr(at + 21));
}

}  // namespace

// --pose-uncertainty: only with --simplemap and without --ini; on Debian's Malaga simplemap (all
// covariances zero) it builds the map of the mean poses, and says so; the probability slice.
TEST(CliInputs, PoseUncertaintyNeedsASimplemapAndUsesItsCovariances) {
  const std::string sm = std::string(RTOG_MRPT_DATASETS) + "/malaga-cs-fac-building.simplemap.gz";
  std::string out;
  EXPECT_EQ(run(std::string("build --tum ") + RTOG_TEST_TUM_DIR + " --stride 16 --pose-uncertainty", &out), 1) << out;
  EXPECT_NE(out.find("--pose-uncertainty needs --simplemap"), std::string::npos) << out;
  const std::string dir = scratch("pose_uncertainty"), plain = dir + "/plain.rtog", blurred = dir + "/blurred.rtog";
  ASSERT_EQ(run("build --simplemap " + sm + " --resolution 0.1 --max-range 15 --out " + plain, &out), 0) << out;
  EXPECT_NE(out.find("pose covariance:  0 of 99 frames have one (not used: poseUncertainty off)"), std::string::npos) << out;
  ASSERT_EQ(run("build --simplemap " + sm + " --resolution 0.1 --max-range 15 --pose-uncertainty --out " + blurred, &out), 0)
      << out;
  EXPECT_NE(out.find("(blurred in: poseUncertainty on)"), std::string::npos) << out;
  EXPECT_EQ(plyOf(blurred), plyOf(plain));  // zero covariances: the mean poses exactly
  const double h = entropyOf(plain);
  EXPECT_GT(h, 0.1);
  EXPECT_LT(h, 1.0);
  const std::string png = dir + "/p.png";
  EXPECT_EQ(run("export " + plain + " --png-probability", &out), 2) << out;  // needs --png
  ASSERT_EQ(run("export " + plain + " --png " + png + " --slice-z 0.35 --png-probability", &out), 0) << out;
  EXPECT_NE(out.find("unknown light blue"), std::string::npos) << out;
}

namespace {

const std::string kSenaRawlog =
    std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

/// A rawlog's bytes as MRPT reads them (the SENA log is gzip-compressed).
std::string plainBytes(const std::string& path) {
  mrpt::io::CFileGZInputStream f(path);
  std::string out;
  char buf[1 << 16];
  for (std::size_t got; (got = f.Read(buf, sizeof buf)) > 0;) out.append(buf, got);
  return out;
}

std::string gzipOf(const std::string& bytes) {
  std::ostringstream os;
  rtog::cli::writeGzip(bytes.data(), bytes.size(), os);
  return os.str();
}

/// One valid 2D scan of one beam.
mrpt::obs::CObservation2DRangeScan::Ptr oneBeamScan() {
  auto scan = mrpt::obs::CObservation2DRangeScan::Create();
  scan->aperture = 3.0f;
  scan->maxRange = 80.0f;
  scan->resizeScan(1);
  scan->setScanRange(0, 12.345f);
  scan->setScanRangeValidity(0, true);
  return scan;
}

/// Serialized bytes holding oneBeamScan() once, its beam count then set to `beams`.
std::string announcing(const mrpt::io::CMemoryStream& mem, std::uint32_t beams) {
  std::string bytes(static_cast<const char*>(mem.getRawBufferData()), mem.getTotalBytesCount());
  // The count is the uint32 just before the ranges (little-endian, as CArchive writes).
  const float range = 12.345f;
  std::string needle(4, '\0');
  needle[0] = 1;
  needle.append(reinterpret_cast<const char*>(&range), 4);
  const auto at = bytes.find(needle);
  EXPECT_NE(at, std::string::npos);
  EXPECT_EQ(bytes.find(needle, at + 1), std::string::npos);
  for (int i = 0; i < 4; ++i) bytes[at + std::size_t(i)] = static_cast<char>((beams >> (8 * i)) & 0xff);
  return bytes;
}

/// The scan as a rawlog entry, announcing `beams`.
std::string scanAnnouncing(std::uint32_t beams) {
  mrpt::io::CMemoryStream mem;
  auto ar = mrpt::serialization::archiveFrom(mem);
  ar << *oneBeamScan();
  return announcing(mem, beams);
}

/// A simplemap of one frame holding the scan, announcing `beams`.
std::string simplemapAnnouncing(std::uint32_t beams) {
  mrpt::maps::CSimpleMap sm;
  auto sf = mrpt::obs::CSensoryFrame::Create();
  sf->insert(oneBeamScan());
  sm.insert(mrpt::poses::CPose3DPDFGaussian::Create(), sf);
  mrpt::io::CMemoryStream mem;
  auto ar = mrpt::serialization::archiveFrom(mem);
  ar << sm;
  return announcing(mem, beams);
}

}  // namespace

// Issue #37: a truncated or corrupt rawlog read as a shorter log (exit 0, no word: half of the
// SENA log gave 111 of its 225 scans), and bytes after its last entry were ignored. Now: one
// error line naming the file and the entry, exit 1, nothing written; --allow-truncated reads up
// to the cut and says what it dropped.
TEST(CliInputs, TruncatedOrCorruptRawlogIsAnError) {
  const std::string d = scratch("rawlog_damage");
  const std::string full = plainBytes(kSenaRawlog);
  ASSERT_EQ(full.size(), 498881u);
  writeAll(d + "/half.rawlog", full.substr(0, full.size() / 2));
  writeAll(d + "/half_gz.rawlog", gzipOf(full).substr(0, readAll(kSenaRawlog).size() / 2));
  writeAll(d + "/tail.rawlog", full + "some bytes after the log");
  std::string out;
  ASSERT_EQ(run("build --resolution 0.2 --rawlog '" + kSenaRawlog + "'", &out), 0) << out;
  EXPECT_NE(out.find(" from 225 scans "), std::string::npos) << out;
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"half.rawlog", "cannot read rawlog '" + d + "/half.rawlog': truncated: the file ends inside entry 224 (byte 248416 of 249440)"},
           {"half_gz.rawlog", "': truncated: the file ends inside entry "},
           {"tail.rawlog", "': corrupt entry 449 (byte 498881 of 498905), 24 bytes before the end"}}) {
    EXPECT_EQ(run("build --resolution 0.2 --rawlog " + d + "/" + file + " --out " + d + "/out.rtog", &out), 1) << out;
    EXPECT_NE(out.find("rtog: error: " ), std::string::npos) << out;
    EXPECT_NE(out.find(message), std::string::npos) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_EQ(entries(d), (std::vector<std::string>{"half.rawlog", "half_gz.rawlog", "tail.rawlog"}));
  }
  EXPECT_EQ(run("build --resolution 0.2 --allow-truncated --rawlog " + d + "/half.rawlog", &out), 0) << out;
  EXPECT_NE(out.find("warning: rawlog '" + d + "/half.rawlog' truncated: the file ends inside entry 224"), std::string::npos)
      << out;
  EXPECT_NE(out.find("reading its first 224 entries, 1024 bytes dropped"), std::string::npos) << out;
  EXPECT_NE(out.find(" from 112 scans "), std::string::npos) << out;
  // Bytes after the last entry are not a truncated entry: still refused.
  EXPECT_EQ(run("build --resolution 0.2 --allow-truncated --rawlog " + d + "/tail.rawlog", &out), 1) << out;
}

// Issue #37: a scan that announces 2^32 - 1 beams in a file of a few hundred bytes made MRPT's
// rawlog reader zero-fill (or, the allocation refused, write through a null pointer) what it
// announced, and rtog build died. Now a clear error, and nothing of it is allocated.
TEST(CliInputs, RawlogLengthFieldsCannotExhaustMemory) {
  const std::string d = scratch("rawlog_hostile");
  const std::string plain = scanAnnouncing(0xFFFFFFFFu);
  std::cout << "hostile rawlog: " << plain.size() << " bytes\n";
  ASSERT_LT(plain.size(), 400u);
  writeAll(d + "/plain.rawlog", plain);
  writeAll(d + "/gz.rawlog", gzipOf(plain));
  writeAll(d + "/one.rawlog", scanAnnouncing(1));  // the same scan as written: read
  const Child ok = spawn({"build", "--resolution", "0.2", "--rawlog", d + "/one.rawlog"});
  EXPECT_EQ(ok.rc, 0) << ok.output;
  EXPECT_NE(ok.output.find(" from 1 scans "), std::string::npos) << ok.output;
  for (const std::string file : {"plain.rawlog", "gz.rawlog"}) {
    const Child c = spawn({"build", "--resolution", "0.2", "--rawlog", d + "/" + file, "--out", d + "/out.rtog"});
    EXPECT_EQ(c.rc, 1) << c.output;
    EXPECT_NE(c.output.find("cannot read rawlog '" + d + "/" + file + "': entry 0 (byte 0 of " +
                            std::to_string(plain.size()) + ") announces more data than the"),
              std::string::npos)
        << c.output;
    std::cout << file << ": peak memory " << c.maxrss_kb / 1024 << " MiB\n";
    EXPECT_LT(c.maxrss_kb, 200 * 1024) << file << ": peak memory " << c.maxrss_kb / 1024 << " MiB";
    EXPECT_FALSE(std::ifstream(d + "/out.rtog").good());
  }
}

// Issue #37: a simplemap went to MRPT's loader unchecked: a scan in it announcing 2^32 - 1 beams
// (a file of a few hundred bytes) was zero-filled or written through a null pointer, as in a
// rawlog. Now checked by the rawlogs' reader: one error line, exit 1, the memory bounded; and a
// truncated simplemap says so.
TEST(CliInputs, SimplemapLengthFieldsCannotExhaustMemory) {
  const std::string d = scratch("simplemap_hostile");
  const std::string plain = simplemapAnnouncing(0xFFFFFFFFu);
  std::cout << "hostile simplemap: " << plain.size() << " bytes\n";
  ASSERT_LT(plain.size(), 1000u);
  writeAll(d + "/plain.simplemap", plain);
  writeAll(d + "/gz.simplemap", gzipOf(plain));
  writeAll(d + "/one.simplemap", simplemapAnnouncing(1));  // the same simplemap as written: read
  const std::string malaga = plainBytes(std::string(RTOG_MRPT_DATASETS) + "/malaga-cs-fac-building.simplemap.gz");
  writeAll(d + "/half.simplemap", malaga.substr(0, malaga.size() / 2));
  // MRPT's loader reads the first of two simplemaps and drops the other silently.
  writeAll(d + "/two.simplemap", simplemapAnnouncing(1) + simplemapAnnouncing(1));
  const Child ok = spawn({"build", "--resolution", "0.2", "--simplemap", d + "/one.simplemap"});
  EXPECT_EQ(ok.rc, 0) << ok.output;
  EXPECT_NE(ok.output.find(" from 1 scans "), std::string::npos) << ok.output;
  for (const std::string file : {"plain.simplemap", "gz.simplemap"}) {
    const Child c = spawn({"build", "--resolution", "0.2", "--simplemap", d + "/" + file, "--out", d + "/out.rtog"});
    EXPECT_EQ(c.rc, 1) << c.output;
    EXPECT_NE(c.output.find("rtog: error: cannot read simplemap '" + d + "/" + file + "': entry 0 (byte 0 of " +
                            std::to_string(plain.size()) + ") announces more data than the"),
              std::string::npos)
        << c.output;
    EXPECT_EQ(std::count(c.output.begin(), c.output.end(), '\n'), 1) << c.output;
    std::cout << file << ": peak memory " << c.maxrss_kb / 1024 << " MiB\n";
    EXPECT_LT(c.maxrss_kb, 200 * 1024) << file << ": peak memory " << c.maxrss_kb / 1024 << " MiB";
    EXPECT_FALSE(std::ifstream(d + "/out.rtog").good());
  }
  std::string out;
  EXPECT_EQ(run("build --resolution 0.2 --simplemap " + d + "/half.simplemap --out " + d + "/out.rtog", &out), 1) << out;
  EXPECT_NE(out.find("rtog: error: cannot read simplemap '" + d + "/half.simplemap': truncated: the file ends inside entry 0"),
            std::string::npos)
      << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_EQ(run("build --resolution 0.2 --simplemap " + d + "/two.simplemap --out " + d + "/out.rtog", &out), 1) << out;
  EXPECT_NE(out.find("rtog: error: cannot read simplemap '" + d + "/two.simplemap': it holds 2 objects, a simplemap file one"),
            std::string::npos)
      << out;
  EXPECT_FALSE(std::ifstream(d + "/out.rtog").good());
}
