// Versioned CSerializable: round trips through memory, files, clone(), and CArchive corruption.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <map>

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "hostile_files.hpp"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using namespace rtog_test;

namespace {

std::map<std::uint64_t, std::pair<rtog::Box, float>> leaves(const rtog::OccupancyMap& m) {
  std::map<std::uint64_t, std::pair<rtog::Box, float>> out;
  m.forEachLeaf([&](const rtog::Box& b, float v) { out[rtog::packKey(b.min)] = {b, v}; });
  return out;
}

CRTreeOccupancyGridMap senaMap(std::size_t frames, bool planar_cache = true) {
  CRTreeOccupancyGridMap m(0.05);
  m.insertionOptions.planarCache = planar_cache;
  m.insertionOptions.maxOccupancyUpdateCertainty = 0.7f;
  m.likelihoodOptions.LF_stdHit = 0.25f;
  m.likelihoodOptions.likelihoodMethod = CRTreeOccupancyGridMap::lmRayTracing;
  for (const auto& f : loadOdometryFrames(dataset(kSena), frames)) f.sf->insertObservationsInto(m, f.pose);
  return m;
}

void expectSame(const CRTreeOccupancyGridMap& a, const CRTreeOccupancyGridMap& b) {
  EXPECT_EQ(a.resolution(), b.resolution());
  EXPECT_EQ(a.map().leafCount(), b.map().leafCount());
  EXPECT_TRUE(leaves(a.map()) == leaves(b.map()));
  EXPECT_EQ(a.insertionOptions.maxOccupancyUpdateCertainty, b.insertionOptions.maxOccupancyUpdateCertainty);
  EXPECT_EQ(a.likelihoodOptions.LF_stdHit, b.likelihoodOptions.LF_stdHit);
  EXPECT_EQ(a.likelihoodOptions.likelihoodMethod, b.likelihoodOptions.likelihoodMethod);
  EXPECT_EQ(a.insertionOptions.planarCache, b.insertionOptions.planarCache);
  EXPECT_EQ(b.map().checkInvariants(), "");
}

}  // namespace

TEST(MapSerialization, MemoryRoundTrip) {
  for (const bool planar_cache : {true, false}) {
    const auto m = senaMap(40, planar_cache);
    ASSERT_GT(m.map().leafCount(), 1000u);
    mrpt::io::CMemoryStream buf;
    auto ar = mrpt::serialization::archiveFrom(buf);
    ar << m;
    buf.Seek(0);
    auto obj = ar.ReadObject();
    auto back = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(obj);
    ASSERT_TRUE(back);
    expectSame(m, *back);
  }
}

// A map being built holds its last scans in the planar cache: written, the cache's coded layers
// are read as cover() would make them (without covering); in the octomap preset, whose cached
// layers are floats, the map is covered first. Either way the bytes are the covered map's.
TEST(MapSerialization, AMapBeingBuiltIsWrittenAsItsCoveredSelf) {
  for (const char* preset : {"mrpt_grid", "octomap"}) {
    SCOPED_TRACE(preset);
    CRTreeOccupancyGridMap m(0.05);
    m.insertionOptions.sensorModelPreset = preset;
    for (const auto& f : loadOdometryFrames(dataset(kSena), 30)) f.sf->insertObservationsInto(m, f.pose);
    std::ostringstream uncovered;
    const std::uint64_t size = m.map().writtenSize();
    m.map().write(uncovered);
    const rtog::InsertStats covering = m.map().flush();
    if (std::string(preset) == "mrpt_grid") {
      EXPECT_GT(covering.leaves_created, 0u);  // it was written uncovered
    }
    std::ostringstream covered;
    m.map().write(covered);
    EXPECT_EQ(uncovered.str().size(), size);
    EXPECT_TRUE(uncovered.str() == covered.str());
    std::istringstream in(uncovered.str());
    EXPECT_TRUE(leaves(rtog::OccupancyMap::read(in)) == leaves(m.map()));
  }
}

TEST(MapSerialization, FileRoundTripAndRepresentation) {
  const auto m = senaMap(40);
  const auto dir = std::filesystem::temp_directory_path() / "rtog_mrpt_test_io";
  std::filesystem::create_directories(dir);
  const std::string prefix = (dir / "sena").string();
  m.saveMetricMapRepresentationToFile(prefix);
  EXPECT_TRUE(std::filesystem::exists(prefix + ".rtog"));
  EXPECT_TRUE(std::filesystem::exists(prefix + ".3Dscene"));
  EXPECT_TRUE(std::filesystem::exists(prefix + "_slice.png"));
  auto back = CRTreeOccupancyGridMap::loadFromFile(prefix + ".rtog");
  expectSame(m, *back);
  std::filesystem::remove_all(dir);
}

// The copy's time is printed, a figure to read, not a bound (doc/benchmarks.md has the map-copy row).
TEST(MapSerialization, CloneAndMultiMapCopyAreEqual) {
  const auto m = senaMap(40);
  const auto t0 = std::chrono::steady_clock::now();
  auto c = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(mrpt::rtti::CObject::Ptr(m.clone()));
  ASSERT_TRUE(c);
  expectSame(m, *c);
  // A copy through serialization, as rbpf-slam does per particle.
  mrpt::maps::CMultiMetricMap mm;
  mm.maps.push_back(std::make_shared<CRTreeOccupancyGridMap>(m));
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  const auto t1 = std::chrono::steady_clock::now();
  for (int i = 0; i < 10; ++i) {
    buf.clear();
    ar << mm;
    buf.Seek(0);
    mrpt::maps::CMultiMetricMap copy;
    ar >> copy;
    ASSERT_EQ(copy.maps.size(), 1u);
    auto cm = copy.mapByClass<CRTreeOccupancyGridMap>();
    ASSERT_TRUE(cm);
    if (i == 0) expectSame(m, *cm);
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count() / 10;
  std::printf("map with %zu leaves: one serialization copy %.2f ms (clone %.2f ms)\n", m.map().leafCount(), ms,
              std::chrono::duration<double, std::milli>(t1 - t0).count());
}

TEST(MapSerialization, CorruptStreamThrows) {
  const auto m = senaMap(5);
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << m;
  const auto n = buf.getTotalBytesCount();
  mrpt::io::CMemoryStream cut;
  cut.assignMemoryNotOwn(buf.getRawBufferData(), n - 40);
  auto ar2 = mrpt::serialization::archiveFrom(cut);
  EXPECT_ANY_THROW(ar2.ReadObject());
}

TEST(MapSerialization, BackedGridRoundTrip) {
  rtog::CRTreeBackedGridMap2D g(0.05);
  for (const auto& f : loadOdometryFrames(dataset(kSena), 20)) f.sf->insertObservationsInto(g, f.pose);
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << g;
  buf.Seek(0);
  auto back = std::dynamic_pointer_cast<rtog::CRTreeBackedGridMap2D>(ar.ReadObject());
  ASSERT_TRUE(back);
  expectSame(g.rtreeMap(), back->rtreeMap());
  EXPECT_EQ(g.getSizeX(), back->getSizeX());
  EXPECT_EQ(g.getSizeY(), back->getSizeY());
  EXPECT_TRUE(g.getRawMap() == back->getRawMap());
}

// rtreeGridMap2D saves what COccupancyGridMap2D saves (its picture and limits, the stock grid's
// own files, byte for byte) and the R-tree map's .rtog, not the cuboids' scene and slice.
TEST(MapSerialization, BackedGridSavesTheGridsFilesAndItsMap) {
  rtog::CRTreeBackedGridMap2D g(0.05);
  for (const auto& f : loadOdometryFrames(dataset(kSena), 20)) f.sf->insertObservationsInto(g, f.pose);
  const auto dir = std::filesystem::temp_directory_path() / "rtog_mrpt_test_backed_io";
  std::filesystem::create_directories(dir);
  const std::string ours = (dir / "ours").string(), stock = (dir / "stock").string();
  g.saveMetricMapRepresentationToFile(ours);
  g.COccupancyGridMap2D::saveMetricMapRepresentationToFile(stock);
  const auto bytes = [](const std::string& file) {
    std::ifstream f(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  for (const char* ext : {".png", "_limits.txt"}) {
    ASSERT_TRUE(std::filesystem::exists(ours + ext)) << ext;
    EXPECT_TRUE(bytes(ours + ext) == bytes(stock + ext)) << ext;
  }
  EXPECT_FALSE(std::filesystem::exists(ours + ".3Dscene"));
  EXPECT_FALSE(std::filesystem::exists(ours + "_slice.png"));
  expectSame(g.rtreeMap(), *CRTreeOccupancyGridMap::loadFromFile(ours + ".rtog"));
  std::filesystem::remove_all(dir);
}

TEST(MapSerialization, VisualizationDrawsOccupiedCuboids) {
  auto m = senaMap(10);
  mrpt::opengl::CSetOfObjects obj;
  m.getVisualizationInto(obj);
  auto tris = obj.getByClass<mrpt::opengl::CSetOfTriangles>();
  ASSERT_TRUE(tris);
  EXPECT_EQ(tris->getTrianglesCount(), 12u * m.map().statistics().occupied_leaves);
  m.renderingOptions.showFree = true;
  mrpt::opengl::CSetOfObjects all;
  m.getVisualizationInto(all);
  EXPECT_EQ(all.getByClass<mrpt::opengl::CSetOfTriangles>()->getTrianglesCount(), 12u * m.map().leafCount());
  m.genericMapParams.enableSaveAs3DObject = false;
  mrpt::opengl::CSetOfObjects none;
  m.getVisualizationInto(none);
  EXPECT_TRUE(none.empty());
}

// The .3Dscene is written set by set (an app saves its map when it holds the most): read back
// by MRPT, its sets hold exactly getVisualizationInto's triangles, in order.
TEST(MapSerialization, TheSceneFileHoldsTheDrawnCuboidsSetBySet) {
  auto m = senaMap(40);
  mrpt::opengl::CSetOfObjects drawn;
  m.getVisualizationInto(drawn);
  const auto all = drawn.getByClass<mrpt::opengl::CSetOfTriangles>();
  ASSERT_TRUE(all);
  const std::size_t cuboids = all->getTrianglesCount() / 12;
  ASSERT_GT(cuboids, 512u) << "the map must fill more than one set of the file";
  const std::string prefix = (std::filesystem::temp_directory_path() / "rtog_scene_sets").string();
  m.saveMetricMapRepresentationToFile(prefix);
  mrpt::opengl::COpenGLScene scene;
  ASSERT_TRUE(scene.loadFromFile(prefix + ".3Dscene"));
  const auto obj = scene.getByClass<mrpt::opengl::CSetOfObjects>();
  ASSERT_TRUE(obj);
  std::size_t sets = 0, t = 0;
  for (const auto& o : *obj) {
    const auto set = std::dynamic_pointer_cast<mrpt::opengl::CSetOfTriangles>(o);
    ASSERT_TRUE(set);
    EXPECT_EQ(set->getName(), "rtog_cuboids");
    ++sets;
    for (std::size_t i = 0; i < set->getTrianglesCount(); ++i, ++t) {
      ASSERT_LT(t, all->getTrianglesCount());
      mrpt::opengl::TTriangle a, b;
      set->getTriangle(i, a);
      all->getTriangle(t, b);
      for (int v = 0; v < 3; ++v) {
        const auto &pa = a.vertices[v].xyzrgba, &pb = b.vertices[v].xyzrgba;
        EXPECT_EQ(pa.pt, pb.pt);
        EXPECT_TRUE(pa.r == pb.r && pa.g == pb.g && pa.b == pb.b && pa.a == pb.a) << "triangle " << t;
      }
    }
  }
  EXPECT_EQ(sets, (cuboids + 511) / 512);
  EXPECT_EQ(t, all->getTrianglesCount());
  for (const char* ext : {".rtog", ".3Dscene", "_slice.png"}) std::filesystem::remove(prefix + ext);
}

// Maps saved by earlier builds (serialization versions 0 and 1; tests/mrpt/data/README.md names
// the commits and the program that wrote them) load with their cells, their options and the
// update rule they were built with (OctoMap's), and save again in today's version.
TEST(MapSerialization, MapsOfEarlierVersionsLoad) {
  for (const char* v : {"v0", "v1"}) {
    SCOPED_TRACE(v);
    const std::string base = std::string(RTOG_MRPT_TEST_DATA) + "/sena20_" + v;
    const auto m = CRTreeOccupancyGridMap::loadFromFile(base + ".gz");
    // The same map in the core format, as both builds wrote it (byte-identical).
    std::ifstream gz(std::string(RTOG_MRPT_TEST_DATA) + "/sena20_core.rtog.gz", std::ios::binary);
    std::istringstream in(gunzip(std::string(std::istreambuf_iterator<char>(gz), {})));
    const rtog::OccupancyMap core = rtog::OccupancyMap::read(in);
    EXPECT_GT(m->map().leafCount(), 1000u);
    EXPECT_TRUE(leaves(m->map()) == leaves(core));
    EXPECT_EQ(m->map().checkInvariants(), "");
    EXPECT_DOUBLE_EQ(m->resolution(), 0.07);
    EXPECT_EQ(m->insertionOptions.maxDistanceInsertion, 12.5f);
    EXPECT_EQ(m->insertionOptions.sensorModelPreset, "octomap");
    EXPECT_EQ(m->likelihoodOptions.LF_stdHit, 0.21f);
    EXPECT_EQ(m->likelihoodOptions.LF_maxRange, 33.0f);
    mrpt::io::CMemoryStream buf;
    auto ar = mrpt::serialization::archiveFrom(buf);
    ar << *m;
    buf.Seek(0);
    const auto back = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(ar.ReadObject());
    ASSERT_TRUE(back);
    expectSame(*m, *back);
    EXPECT_EQ(back->insertionOptions.sensorModelPreset, "octomap");
  }
}
