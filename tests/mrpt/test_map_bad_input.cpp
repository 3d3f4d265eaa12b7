// Bad observations and files not covered elsewhere (doc/reliability.md's table): point arrays
// of different lengths, a stored version this build does not know. Each is a clear error and
// leaves the map as it was.
#include <gtest/gtest.h>

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
  ASSERT_EQ(static_cast<unsigned char>(bytes[version_at]), 2u) << "the version byte moved: update the test";
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
