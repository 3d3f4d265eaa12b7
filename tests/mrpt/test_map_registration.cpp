// The plugin's classes are in MRPT's class registry as soon as the library is loaded, whatever
// the compiler (built with clang, a constructor-attribute registration ran before the class ids
// were initialized and every CArchive read failed with "not registered"); and the MRPT-format
// map file reads back through CArchive and through `rtog info`.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/register_classes.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

// Runs first in its own process (ctest runs each case alone): nothing has constructed a map or
// called registerMrptClasses(), so only the load-time registration can have put them there.
TEST(MapRegistration, ClassesAreRegisteredWhenTheLibraryLoads) {
  const auto* a = mrpt::rtti::findRegisteredClass("rtog::CRTreeOccupancyGridMap");
  const auto* b = mrpt::rtti::findRegisteredClass("rtog::CRTreeBackedGridMap2D");
  EXPECT_EQ(a, CLASS_ID(CRTreeOccupancyGridMap));
  EXPECT_EQ(b, CLASS_ID(rtog::CRTreeBackedGridMap2D));
  ASSERT_TRUE(a && b);
  auto obj = a->createObject();
  EXPECT_TRUE(std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(obj));
}

TEST(MapRegistration, ArchiveReadsBothClassesByName) {
  rtog::CRTreeBackedGridMap2D g(0.1);
  for (const auto& f : loadOdometryFrames(dataset(kSena), 5)) f.sf->insertObservationsInto(g, f.pose);
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << g << g.rtreeMap();
  buf.Seek(0);
  auto back_grid = std::dynamic_pointer_cast<rtog::CRTreeBackedGridMap2D>(ar.ReadObject());
  auto back_map = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(ar.ReadObject());
  ASSERT_TRUE(back_grid && back_map);
  EXPECT_EQ(back_grid->rtreeMap().map().leafCount(), g.rtreeMap().map().leafCount());
  EXPECT_EQ(back_map->map().leafCount(), g.rtreeMap().map().leafCount());
}

// `rtog info` on the map file the MRPT apps write (saveToFile: a gzip CArchive).
TEST(MapRegistration, CliInfoReadsAnMrptFormatMap) {
  CRTreeOccupancyGridMap m(0.1);
  for (const auto& f : loadOdometryFrames(dataset(kSena), 10)) f.sf->insertObservationsInto(m, f.pose);
  ASSERT_GT(m.map().leafCount(), 100u);
  const std::string dir = ::testing::TempDir() + "/rtog_registration_" + std::to_string(getpid());
  const std::string file = dir + "/sena.rtog", out_file = dir + "/info.json";
  ASSERT_EQ(std::system(("mkdir -p '" + dir + "'").c_str()), 0);
  m.saveToFile(file);
  const int rc = std::system((std::string(RTOG_EXE) + " info --json '" + file + "' > '" + out_file + "' 2>&1").c_str());
  std::stringstream ss;
  ss << std::ifstream(out_file).rdbuf();
  ASSERT_EQ(WEXITSTATUS(rc), 0) << ss.str();
  EXPECT_NE(ss.str().find("\"leaves\": " + std::to_string(m.map().leafCount())), std::string::npos) << ss.str();
  std::system(("rm -rf '" + dir + "'").c_str());
}
