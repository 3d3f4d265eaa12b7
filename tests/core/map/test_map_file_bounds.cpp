// The core format's leaf count is checked against the bytes a stream holds before any leaf is
// read; a stream that cannot tell its size (a pipe) fails as it runs out, having stored only
// the leaves it held.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <streambuf>

#include "rtog/core/occupancy_map.hpp"

namespace {

rtog::OccupancyMap smallMap() {
  rtog::MapParams p;
  p.resolution = 0.1;
  rtog::OccupancyMap m(p);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 90; ++i) pts.emplace_back(3.0f * std::cos(i * 0.07f), 3.0f * std::sin(i * 0.07f), 0.05f);
  m.insertPointCloud(Eigen::Vector3d(0.05, 0.05, 0.05), pts);
  return m;
}

std::string smallMapBytes() {
  std::ostringstream os;
  smallMap().write(os);
  return os.str();
}

// magic, version, seven doubles, the merge policy, two R-tree capacities, then the count
constexpr std::size_t kCountAt = 8 + 4 + 7 * 8 + 1 + 4 + 4;

/// A stream buffer over bytes that cannot seek, as a pipe.
struct PipeBuf : std::streambuf {
  explicit PipeBuf(std::string& s) { setg(s.data(), s.data(), s.data() + s.size()); }
};

std::string readError(std::istream& in) {
  try {
    rtog::OccupancyMap::read(in);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(MapFileBounds, ALeafCountTheStreamCannotHoldIsRefusedBeforeReading) {
  std::string bytes = smallMapBytes();
  std::uint64_t count = 0;
  std::memcpy(&count, &bytes[kCountAt], sizeof(count));
  ASSERT_EQ(count, smallMap().leafCount());  // the layout is as assumed
  const std::uint64_t huge = std::uint64_t{1} << 35;
  std::memcpy(&bytes[kCountAt], &huge, sizeof(huge));
  std::istringstream file(bytes);
  EXPECT_NE(readError(file).find("the leaf count 34359738368 needs"), std::string::npos) << readError(file);
  PipeBuf buf(bytes);
  std::istream pipe(&buf);
  EXPECT_NE(readError(pipe).find("truncated stream while reading"), std::string::npos) << readError(pipe);
  // The unchanged bytes still load, from either.
  std::memcpy(&bytes[kCountAt], &count, sizeof(count));
  std::istringstream good(bytes);
  EXPECT_EQ(readError(good), "");
  PipeBuf good_buf(bytes);
  std::istream good_pipe(&good_buf);
  EXPECT_EQ(readError(good_pipe), "");
}

TEST(MapFileBounds, WrittenSizeIsTheBytesWritten) {
  const rtog::OccupancyMap m = smallMap();
  EXPECT_EQ(smallMapBytes().size(), m.writtenSize());
}

// Version 2 stores a brick's key and leaf count before its leaves: a key beyond the key range
// (its cells' keys would overflow) and a count beyond a brick's cells are refused by name.
TEST(MapFileBounds, AMalformedBrickIsRefused) {
  constexpr std::size_t kBrickAt = kCountAt + 8;
  for (const int field : {0, 3}) {
    std::string bytes = smallMapBytes();
    const std::uint32_t bad = field == 0 ? 0x7FFFFFF0u : 5000u;
    std::memcpy(&bytes[kBrickAt + 4 * static_cast<std::size_t>(field)], &bad, sizeof(bad));
    std::istringstream file(bytes);
    EXPECT_NE(readError(file).find("malformed brick"), std::string::npos) << field << ": " << readError(file);
  }
}

}  // namespace
