// The core format's leaf count is checked against the bytes a stream holds before any leaf is
// read; a stream that cannot tell its size (a pipe) fails as it runs out, having stored only
// the leaves it held.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <streambuf>

#include "rtog/core/occupancy_map.hpp"

namespace {

std::string smallMapBytes() {
  rtog::MapParams p;
  p.resolution = 0.1;
  rtog::OccupancyMap m(p);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 90; ++i) pts.emplace_back(3.0f * std::cos(i * 0.07f), 3.0f * std::sin(i * 0.07f), 0.05f);
  m.insertPointCloud(Eigen::Vector3d(0.05, 0.05, 0.05), pts);
  std::ostringstream os;
  m.write(os);
  return os.str();
}

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
  // magic, version, seven doubles, the merge policy, two R-tree capacities, then the count
  constexpr std::size_t kCountAt = 8 + 4 + 7 * 8 + 1 + 4 + 4;
  std::uint64_t count = 0;
  std::memcpy(&count, &bytes[kCountAt], sizeof(count));
  ASSERT_EQ((bytes.size() - kCountAt - 8 - 8) / 28, count);  // the layout is as assumed
  const std::uint64_t huge = std::uint64_t{1} << 35;
  std::memcpy(&bytes[kCountAt], &huge, sizeof(huge));
  std::istringstream file(bytes);
  EXPECT_NE(readError(file).find("the leaf count 34359738368 needs"), std::string::npos) << readError(file);
  PipeBuf buf(bytes);
  std::istream pipe(&buf);
  EXPECT_NE(readError(pipe).find("truncated stream while reading leaf"), std::string::npos);
  // The unchanged bytes still load, from either.
  std::memcpy(&bytes[kCountAt], &count, sizeof(count));
  std::istringstream good(bytes);
  EXPECT_EQ(readError(good), "");
  PipeBuf good_buf(bytes);
  std::istream good_pipe(&good_buf);
  EXPECT_EQ(readError(good_pipe), "");
}

}  // namespace
