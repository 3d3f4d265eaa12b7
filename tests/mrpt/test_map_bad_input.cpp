// Bad observations and files not covered elsewhere (doc/reliability.md's table): point arrays
// of different lengths, a stored version this build does not know. Each is a clear error and
// leaves the map as it was.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "hostile_files.hpp"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

std::string bytesOf(const CRTreeOccupancyGridMap& m) { return archiveBytes(m); }

// A map holding the first scans of SENA, so that "unchanged" means something.
CRTreeOccupancyGridMap senaMap() {
  CRTreeOccupancyGridMap m(0.05);
  for (const auto& f : loadOdometryFrames(dataset(kSena), 5)) f.sf->insertObservationsInto(m, f.pose);
  return m;
}

void expectRefused(CRTreeOccupancyGridMap& m, const mrpt::obs::CObservation& o, const std::string& what) {
  const std::string before = bytesOf(m);
  try {
    m.insertObservation(o);
    ADD_FAILURE() << "inserted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
  EXPECT_EQ(bytesOf(m), before) << "the map changed";
}

}  // namespace

TEST(MapBadInput, PointArraysOfDifferentLengthsAreRefused) {
  CRTreeOccupancyGridMap m = senaMap();
  mrpt::obs::CObservation3DRangeScan depth;
  depth.hasPoints3D = true;
  depth.points3D_x = {1.0f, 2.0f, 3.0f};
  depth.points3D_y = {0.0f, 0.5f};  // one short: read past it, it would be undefined behaviour
  depth.points3D_z = {0.1f, 0.1f, 0.1f};
  expectRefused(m, depth, "points3D arrays differ in length (x 3, y 2, z 3)");
  // A Velodyne scan's decoded cloud.
  mrpt::obs::CObservationVelodyneScan velo;
  velo.point_cloud.x = {2.0f, 3.0f, 4.0f, 5.0f};
  velo.point_cloud.y = {1.0f, 1.0f, 1.0f, 1.0f};
  velo.point_cloud.z = {0.1f, 0.1f};
  expectRefused(m, velo, "point_cloud arrays differ in length (x 4, y 4, z 2)");
}

TEST(MapBadInput, AStoredVersionFromTheFutureIsRefused) {
  const CRTreeOccupancyGridMap m = senaMap();
  std::string bytes = bytesOf(m);
  // CArchive writes the class name, then the version byte, then the object.
  const std::string name = "rtog::CRTreeOccupancyGridMap";
  const auto at = bytes.find(name);
  ASSERT_NE(at, std::string::npos);
  const std::size_t version_at = at + name.size();
  ASSERT_EQ(static_cast<unsigned char>(bytes[version_at]), 6u) << "the version byte moved: update the test";
  bytes[version_at] = 9;
  mrpt::io::CMemoryStream in;
  in.assignMemoryNotOwn(bytes.data(), bytes.size());
  auto ar = mrpt::serialization::archiveFrom(in);
  CRTreeOccupancyGridMap target = senaMap();
  const std::string before = bytesOf(target);
  try {
    ar >> target;
    ADD_FAILURE() << "loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("version"), std::string::npos) << e.what();
  }
  EXPECT_EQ(bytesOf(target), before);
}

// loadFromFile reads the whole file: bytes after the map, inside the gzip stream or after it,
// are an error (zlib's gzread skipped those after the member without a word); a plain
// (uncompressed) archive loads, as through CFileGZInputStream; a directory says so.
TEST(MapBadInput, LoadFromFileRefusesTrailingBytes) {
  const CRTreeOccupancyGridMap m = senaMap();
  const ScratchFile f;
  m.saveToFile(f.path);
  const std::string gz = [&] {
    std::ifstream in(f.path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  const auto write = [&](const std::string& bytes) { std::ofstream(f.path, std::ios::binary | std::ios::trunc) << bytes; };
  const auto error = [&]() -> std::string {
    try {
      CRTreeOccupancyGridMap::loadFromFile(f.path);
      return "";
    } catch (const std::exception& e) {
      return e.what();
    }
  };
  write(gz);
  EXPECT_EQ(error(), "");
  EXPECT_TRUE(bytesOf(*CRTreeOccupancyGridMap::loadFromFile(f.path)) == bytesOf(m));
  write(gz + "junk");
  EXPECT_NE(error().find("4 trailing bytes after the map"), std::string::npos) << error();
  write(gzip(bytesOf(m) + "xyz"));
  EXPECT_NE(error().find("3 trailing bytes after the map"), std::string::npos) << error();
  write(bytesOf(m));
  EXPECT_EQ(error(), "");
  write(bytesOf(m) + "z");
  EXPECT_NE(error().find("1 trailing byte after the map"), std::string::npos) << error();
  write("");
  EXPECT_NE(error().find("the file is empty"), std::string::npos) << error();
  EXPECT_NE(error().find(f.path), std::string::npos) << error();
  try {
    CRTreeOccupancyGridMap::loadFromFile("/tmp");
    ADD_FAILURE() << "a directory loaded";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("it is a directory"), std::string::npos) << e.what();
  }
}
