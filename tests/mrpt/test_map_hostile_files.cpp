// MRPT-format map files (CArchive) as a damaged disk or an attacker would hand them over: length
// fields that promise terabytes, flipped bits in the options, streams that end early. Each is a
// clear error or a map whose options pass the checks an .ini's pass; nothing huge is allocated,
// and a map a failed load was read into is as it was.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <random>

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>

#include "hostile_files.hpp"
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

CRTreeOccupancyGridMap senaMap(std::size_t frames) {
  CRTreeOccupancyGridMap m(0.1);
  for (const auto& f : loadOdometryFrames(dataset(kSena), frames)) f.sf->insertObservationsInto(m, f.pose);
  return m;
}

/// Reads `bytes` (an uncompressed archive) into `into`; the exception's message, "" if none.
std::string readInto(const std::string& bytes, mrpt::serialization::CSerializable& into) {
  mrpt::io::CMemoryStream mem;
  mem.assignMemoryNotOwn(bytes.data(), bytes.size());
  auto ar = mrpt::serialization::archiveFrom(mem);
  try {
    ar >> into;
  } catch (const std::exception& e) {
    return e.what()[0] ? e.what() : "(empty message)";
  }
  return "";
}

std::string writeFile(const std::string& name, const std::string& bytes) {
  const std::string path = ::testing::TempDir() + "/rtog_hostile_" + std::to_string(getpid()) + "_" + name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

/// Every check an .ini's values pass, on a loaded map; "" if all pass.
std::string optionErrors(const CRTreeOccupancyGridMap& m) {
  try {
    m.insertionOptions.validate();
    m.likelihoodOptions.validate();
    m.gridViewOptions.validate();
    m.matchingOptions.validate();
    m.map().params().validate();
  } catch (const std::exception& e) {
    return e.what();
  }
  const rtog::TGridFrame2D& f = m.gridFrame();
  if (!(f.x_min < f.x_max && f.y_min < f.y_max && f.resolution == float(m.resolution()))) return "bad grid frame";
  return m.map().checkInvariants();
}

TEST(HostileFiles, LengthFieldsAllocateNothingTheyPromise) {
  std::string owa = archiveBytes(CRTreeOccupancyGridMap(0.1));
  std::string weights(4, '\0');
  poke(weights, 0, std::uint32_t{100});
  poke(owa, owa.find(weights + std::string("\x0a\xd7\x23\x3c", 4)), std::uint32_t{1} << 28);
  const struct {
    const char* name;
    std::string file;
    const char* message;
  } cases[] = {
      {"block", hugeBlockFile(std::uint64_t{1} << 40), "truncated stream (map block: 1099511627776 bytes announced"},
      // 1 GiB each: enough to see, not enough to take the machine down if a change brings the
      // allocation back.
      {"block30", hugeBlockFile(std::uint64_t{1} << 30), "truncated stream (map block: 1073741824 bytes announced"},
      {"string", hugeStringFile(1u << 30), "corrupt stream (sensorModel: a 1073741824-byte string"},
      {"owa", gzip(owa), "corrupt stream (OWA_weights: 268435456 values"},
  };
  const CRTreeOccupancyGridMap before = senaMap(3);
  const std::string before_bytes = archiveBytes(before);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    std::cout << c.name << ": a file of " << c.file.size() << " bytes\n";
    const double peak0 = peakMiB();
    const std::string path = writeFile(c.name, c.file);
    try {
      CRTreeOccupancyGridMap::loadFromFile(path);
      ADD_FAILURE() << "loaded";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << e.what();
    }
    std::remove(path.c_str());
    // Read into a map that holds cells: an error, and the map as it was.
    CRTreeOccupancyGridMap m = before;
    EXPECT_NE(readInto(gunzip(c.file), m).find(c.message), std::string::npos);
    EXPECT_TRUE(archiveBytes(m) == before_bytes) << "the map a failed load was read into changed";
    EXPECT_LT(peakMiB() - peak0, 64.0) << "peak memory grew by " << peakMiB() - peak0 << " MiB";
  }
}

// The COccupancyGridMap2D part of rtreeGridMap2D: MRPT's own reader sizes the grid from the
// stored extent and zero-fills it before reading a cell.
TEST(HostileFiles, GridExtentsAllocateNothingTheyPromise) {
  static constexpr float kMinusTen = -10.0f;  // y_min, where the flat case expects it
  const rtog::CRTreeBackedGridMap2D grid(0.1);  // -10..10 m: 200 x 200 cells
  const std::string bytes = archiveBytes(grid);
  std::string header(1, '\x08');
  header.resize(1 + 4 * 4);
  poke(header, 1, std::uint32_t{200});
  poke(header, 5, std::uint32_t{200});
  poke(header, 9, -10.0f);
  poke(header, 13, 10.0f);
  const std::size_t at = bytes.find(header);
  ASSERT_NE(at, std::string::npos);
  std::string wide = bytes, huge = bytes, nan = bytes;
  poke(wide, at + 1, std::uint32_t{1000100});  // 100 km x 20 m, consistent, cells not there
  poke(wide, at + 13, 1.0e5f);
  poke(huge, at + 13, 1.0e30f);  // an exponent bit
  poke(nan, at + 13, std::numeric_limits<float>::quiet_NaN());
  // Found by rtog_fuzz_mrpt_archive: a side of 0 cells made the product of the sides small, and
  // the other side (1e12 cells) was cast to 32 bits (undefined).
  std::string flat = bytes;
  poke(flat, at + 13, 1.0e11f);
  poke(flat, at + 21, -9.97f);  // y_max: 0.03 m above y_min, 0 cells
  ASSERT_EQ(flat.substr(at + 17, 4), std::string(reinterpret_cast<const char*>(&kMinusTen), 4));
  for (const auto& [name, file, message] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"wide", wide, "truncated stream (grid cells: 200020000 bytes announced"},
           {"huge", huge, "corrupt stream (grid geometry: rtog mrpt_grid: a grid of more than 2^31 cells"},
           {"nan", nan, "corrupt stream (grid geometry"},
           {"flat", flat, "corrupt stream (grid geometry: rtog mrpt_grid: a grid of more than 2^31 cells"}}) {
    SCOPED_TRACE(name);
    const double peak0 = peakMiB();
    rtog::CRTreeBackedGridMap2D into(0.1);
    const std::string into_bytes = archiveBytes(into);
    EXPECT_NE(readInto(file, into).find(message), std::string::npos) << readInto(file, into);
    EXPECT_TRUE(archiveBytes(into) == into_bytes) << "the grid a failed load was read into changed";
    EXPECT_LT(peakMiB() - peak0, 64.0) << "peak memory grew by " << peakMiB() - peak0 << " MiB";
  }
}

// The backed grid's likelihood options are COccupancyGridMap2D's, which MRPT reads unchecked:
// stored with a beam step of 0, its likelihood field would loop forever. Refused on load, with
// the grid read into unchanged.
TEST(HostileFiles, BackedGridLikelihoodStepsOfZeroAreRefused) {
  const char* keys[] = {"LF_decimation", "MI_skip_rays", "rayTracing_decimation", "consensus_takeEachRange"};
  for (int which = 0; which < 4; ++which) {
    SCOPED_TRACE(keys[which]);
    rtog::CRTreeBackedGridMap2D stored(0.1);
    auto& lo = stored.likelihoodOptions;
    if (which == 0) lo.LF_decimation = 0;
    if (which == 1) lo.MI_skip_rays = 0;
    if (which == 2) lo.rayTracing_decimation = 0;
    if (which == 3) lo.consensus_takeEachRange = 0;
    rtog::CRTreeBackedGridMap2D into(0.1);
    const std::string into_bytes = archiveBytes(into);
    const std::string error = readInto(archiveBytes(stored), into);
    EXPECT_NE(error.find(keys[which]), std::string::npos) << "loaded: '" << error << "'";
    EXPECT_TRUE(archiveBytes(into) == into_bytes) << "the grid a failed load was read into changed";
  }
}

// Bit flips in a real map's options (fixed seed): each load fails with a message or gives a map
// whose options pass every check an .ini's values pass.
TEST(HostileFiles, FlippedOptionBitsFailOrValidate) {
  const std::string bytes = archiveBytes(senaMap(5));
  const std::size_t options_end = blockLengthOffset(bytes);  // the map block has its own checksum
  std::mt19937 rng(15);
  std::size_t loaded = 0, refused = 0;
  for (int i = 0; i < 200; ++i) {
    std::string flipped = bytes;
    const std::size_t bit = std::uniform_int_distribution<std::size_t>(0, options_end * 8 - 1)(rng);
    flipped[bit / 8] = static_cast<char>(flipped[bit / 8] ^ (1 << (bit % 8)));
    CRTreeOccupancyGridMap m(0.1);
    const std::string error = readInto(flipped, m);
    if (!error.empty()) {
      ++refused;
      continue;
    }
    ++loaded;
    EXPECT_EQ(optionErrors(m), "") << "bit " << bit << " (byte " << bit / 8 << ") loaded invalid options";
  }
  std::cout << "200 flipped option bits: " << refused << " refused with a message, " << loaded
            << " loaded with valid options\n";
  EXPECT_GT(refused, 0u);
}

// Cut anywhere, a stream read into a map leaves it as it was.
TEST(HostileFiles, TruncatedStreamsLeaveTheMapUnchanged) {
  const std::string bytes = archiveBytes(senaMap(5));
  CRTreeOccupancyGridMap m = senaMap(2);
  m.likelihoodOptions.LF_stdHit = 0.42f;
  const std::string m_bytes = archiveBytes(m);
  std::size_t cuts = 0;
  for (std::size_t n = 0; n < bytes.size(); n += n < 600 ? 3 : 997, ++cuts) {
    EXPECT_NE(readInto(bytes.substr(0, n), m), "") << "a stream cut at " << n << " bytes loaded";
    ASSERT_TRUE(archiveBytes(m) == m_bytes) << "a stream cut at " << n << " bytes changed the map";
  }
  EXPECT_EQ(readInto(bytes, m), "");  // and the whole stream loads
  EXPECT_GT(cuts, 200u);
}

}  // namespace

namespace {

/// What loading `path` in a child process said, and how much its peak resident memory grew [MiB].
std::pair<std::string, double> loadInAChild(const std::string& path) {
  int fds[2];
  if (pipe(fds) != 0) throw std::runtime_error("no pipe");
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    const double peak0 = peakMiB();
    std::string said = "loaded";
    try {
      CRTreeOccupancyGridMap::loadFromFile(path);
    } catch (const std::exception& e) {
      said = e.what();
    }
    said = std::to_string(peakMiB() - peak0) + "\n" + said;
    if (write(fds[1], said.data(), said.size()) < 0) _exit(2);
    _exit(0);
  }
  close(fds[1]);
  std::string got;
  char buf[4096];
  for (ssize_t r; (r = read(fds[0], buf, sizeof buf)) > 0;) got.append(buf, static_cast<std::size_t>(r));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  const auto nl = got.find('\n');
  if (!WIFEXITED(status) || nl == std::string::npos) return {"the child died: " + got, 1e9};
  return {got.substr(nl + 1), std::stod(got.substr(0, nl))};
}

}  // namespace

// Issue #37: a gzip file of 1.1 MiB whose map block announces 2^40 bytes and holds 256 MiB of
// zeros made the loader buffer every zero before it looked at the block's magic, for a
// "truncated stream" at the end. Now the block is parsed as it arrives: its magic is refused.
TEST(HostileFiles, AHugeBlockOfZerosIsRefusedAsItArrives) {
  std::string a = archiveBytes(CRTreeOccupancyGridMap(0.1));
  const std::size_t at = blockLengthOffset(a);
  a.resize(at);
  a.append(8, '\0');
  poke(a, at, std::uint64_t{1} << 40);
  const std::string path = writeFile("zeros", "");
  {
    mrpt::io::CFileGZOutputStream out;
    ASSERT_TRUE(out.open(path));
    out.Write(a.data(), a.size());
    const std::string zeros(1 << 20, '\0');
    for (int i = 0; i < 256; ++i) out.Write(zeros.data(), zeros.size());
  }
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  const auto size = static_cast<long>(f.tellg());
  std::cout << "a file of " << size << " bytes\n";
  EXPECT_LT(size, 2 << 20);
  const auto [said, grew] = loadInAChild(path);
  std::remove(path.c_str());
  std::cout << "peak memory grew by " << grew << " MiB: " << said << "\n";
  EXPECT_NE(said.find("rtog map: not an rtog map (bad magic)"), std::string::npos) << said;
  EXPECT_LT(grew, 32.0);
}
