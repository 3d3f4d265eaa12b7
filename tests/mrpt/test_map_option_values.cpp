// .ini values read as a person means them (booleans, whole numbers, inert keys), and the
// per-scan cell budget's key; test_map_options.cpp has the rest of the options' tests.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/exceptions.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/ini_checks.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;

namespace {

const auto fromIni = &rtog_test::multiMapFromIni;

}  // namespace

// ---- issue #37: values read as a person means them -----------------------------------------

namespace {

/// The message of what loading `ini` throws, or "" if it loads.
std::string loadError(const std::string& ini) {
  try {
    fromIni(ini);
  } catch (const mrpt::ExceptionWithCallBackBase& e) {
    return e.originalWhat;  // ours, as thrown: MRPT's what() cuts it at the first ']'
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::string oneMap(const std::string& type, const std::string& section, const std::string& lines) {
  return "[MappingApplication]\n" + type + "_count=1\n[MappingApplication_" + type + "_00_" + section + "]\n" + lines +
         "\n";
}

bool discretizeOf(const std::string& type, const std::string& value) {
  auto mm = fromIni(oneMap(type, "insertOpts", "sensorModelPreset=octomap\ndiscretize = " + value));
  if (auto m = mm.mapByClass<CRTreeOccupancyGridMap>()) return m->insertionOptions.discretize;
  return mm.mapByClass<rtog::CRTreeBackedGridMap2D>()->rtreeMap().insertionOptions.discretize;
}

}  // namespace

// MRPT's read_bool takes true/false, yes/no and a number, and reads any other word as false:
// "discretize = on" was off without a word. Both map types take on/off as well, in any case.
TEST(MapOptions, BooleansAreReadAsMeant) {
  for (const std::string type : {"rtreeOccupancyGrid", "rtreeGridMap2D"}) {
    for (const std::string v : {"on", "ON", "true", "True", "yes", "1", "on // a comment"})
      EXPECT_TRUE(discretizeOf(type, v)) << type << ": discretize = " << v;
    for (const std::string v : {"off", "OFF", "false", "no", "0"}) EXPECT_FALSE(discretizeOf(type, v)) << type << ": " << v;
  }  // Where MRPT's own loaders read them: the generic map parameters of every _creationOpts, the
  // backed grid's likelihood section.
  auto mm = fromIni("[MappingApplication]\nrtreeGridMap2D_count=1\n[MappingApplication_rtreeGridMap2D_00_creationOpts]\n"
                    "enableObservationInsertion = off\n[MappingApplication_rtreeGridMap2D_00_likelihoodOpts]\n"
                    "LF_useSquareDist = on\nenableLikelihoodCache = Off\n");
  const auto g = mm.mapByClass<rtog::CRTreeBackedGridMap2D>();
  EXPECT_FALSE(g->genericMapParams.enableObservationInsertion);
  EXPECT_TRUE(g->likelihoodOptions.LF_useSquareDist);
  EXPECT_FALSE(g->likelihoodOptions.enableLikelihoodCache);
  auto mr = fromIni(oneMap("rtreeOccupancyGrid", "creationOpts", "enableSaveAs3DObject = no"));
  EXPECT_FALSE(mr.mapByClass<CRTreeOccupancyGridMap>()->genericMapParams.enableSaveAs3DObject);
}

// Any other word is refused, naming section, key and the words taken: in the sections rtog reads
// and in the backed grid's likelihood section, which MRPT's own loader reads.
TEST(MapOptions, OtherBooleanWordsAreRefused) {
  for (const auto& [type, section, line, key] : std::vector<std::array<std::string, 4>>{
           {"rtreeOccupancyGrid", "insertOpts", "discretize = enabled", "discretize"},
           {"rtreeOccupancyGrid", "insertOpts", "planarCache = 2", "planarCache"},
           {"rtreeOccupancyGrid", "insertOpts", "poseUncertainty = onn", "poseUncertainty"},
           {"rtreeOccupancyGrid", "likelihoodOpts", "enableLikelihoodCache = y", "enableLikelihoodCache"},
           {"rtreeOccupancyGrid", "likelihoodOpts", "scanLikelihoodOnGridView = nope", "scanLikelihoodOnGridView"},
           {"rtreeGridMap2D", "insertOpts", "useMapAltitude = sometimes", "useMapAltitude"},
           {"rtreeGridMap2D", "likelihoodOpts", "LF_useSquareDist = si", "LF_useSquareDist"},
           {"rtreeGridMap2D", "likelihoodOpts", "enableLikelihoodCache = enabled", "enableLikelihoodCache"},
           // MRPT's own generic map parameters, read by it from every _creationOpts
           {"rtreeOccupancyGrid", "creationOpts", "enableObservationInsertion = nein", "enableObservationInsertion"},
           {"rtreeGridMap2D", "creationOpts", "enableSaveAs3DObject = on/off", "enableSaveAs3DObject"}}) {
    const std::string err = loadError(oneMap(type, section, line));
    SCOPED_TRACE(type + " " + line + ": " + err);
    EXPECT_NE(err.find("[MappingApplication_" + type + "_00_" + section + "] " + key + ":"), std::string::npos);
    EXPECT_NE(err.find("true/false, yes/no, on/off or 1/0"), std::string::npos);
  }
}

// MRPT reads the leading number of a value: "resolution = 0.1abc" was 0.1, "decimation = 3.5"
// was 3. Every numeric key the loaders read takes the whole value or is refused by name.
TEST(MapOptions, NumbersWithTrailingTextAreRefused) {
  for (const auto& [type, section, line, key] : std::vector<std::array<std::string, 4>>{
           {"rtreeOccupancyGrid", "creationOpts", "resolution = 0.1abc", "resolution"},
           {"rtreeGridMap2D", "creationOpts", "resolution = 0.1abc", "resolution"},
           {"rtreeOccupancyGrid", "creationOpts", "min_x = -5 m", "min_x"},
           {"rtreeOccupancyGrid", "creationOpts", "gridView_maxZ = 2,5", "gridView_maxZ"},
           {"rtreeOccupancyGrid", "creationOpts", "priorConfidence = 0.8 ; trusted", "priorConfidence"},
           {"rtreeOccupancyGrid", "insertOpts", "maxDistanceInsertion = 5m", "maxDistanceInsertion"},
           {"rtreeOccupancyGrid", "insertOpts", "decimation = 3.5", "decimation"},
           {"rtreeOccupancyGrid", "insertOpts", "threads = 4294967298", "threads"},
           {"rtreeOccupancyGrid", "insertOpts", "clampingMax = 1e40", "clampingMax"},
           {"rtreeOccupancyGrid", "insertOpts", "maxOccupancyUpdateCertainty =", "maxOccupancyUpdateCertainty"},
           {"rtreeOccupancyGrid", "likelihoodOpts", "LF_stdHit = 0.2x", "LF_stdHit"},
           {"rtreeOccupancyGrid", "likelihoodOpts", "MI_skip_rays = -1", "MI_skip_rays"},
           {"rtreeOccupancyGrid", "matchingOpts", "matching2D_maxZ = 1e", "matching2D_maxZ"},
           {"rtreeGridMap2D", "insertOpts", "mapAltitude = 0.3.1", "mapAltitude"},
           {"rtreeGridMap2D", "likelihoodOpts", "LF_zHit = 0.9,", "LF_zHit"},
           {"rtreeGridMap2D", "likelihoodOpts", "LF_decimation = 5five", "LF_decimation"},
           {"rtreeGridMap2D", "likelihoodOpts", "MI_skip_rays = -1", "MI_skip_rays"}}) {
    const std::string err = loadError(oneMap(type, section, line));
    SCOPED_TRACE(type + " " + line + ": " + err);
    EXPECT_NE(err.find("[MappingApplication_" + type + "_00_" + section + "] " + key + ":"), std::string::npos);
  }
  // What MRPT itself writes and strips still reads: exponents, signs, a " //" comment.
  auto mm = fromIni(oneMap("rtreeOccupancyGrid", "insertOpts",
                           "sensorModelPreset=octomap\nmaxDistanceInsertion = 1.5e1 // metres\nmapAltitude=-0.25\n"
                           "useMapAltitude=true\ndecimation=+2"));
  const auto& io = mm.mapByClass<CRTreeOccupancyGridMap>()->insertionOptions;
  EXPECT_FLOAT_EQ(io.maxDistanceInsertion, 15.0f);
  EXPECT_FLOAT_EQ(io.mapAltitude, -0.25f);
  EXPECT_EQ(io.decimation, 2);
}

// A key this project knows but that the section's other options make inert is told once, by
// name and why: the rangeNoise sigmas under another sensor model, clamping in the mrpt_grid
// preset, mapAltitude without useMapAltitude, a prior's settings without a prior.
TEST(MapOptions, InertKeysAreTold) {
  const auto warnings = [](const std::string& ini) {
    testing::internal::CaptureStderr();
    fromIni(ini);
    fromIni(ini);
    return testing::internal::GetCapturedStderr();
  };
  const std::string noise = warnings(oneMap("rtreeOccupancyGrid", "insertOpts",
                                            "sensorModelPreset=octomap\nsensorModel=beam\nrangeNoiseStd=0.02"));
  const std::string want = "[MappingApplication_rtreeOccupancyGrid_00_insertOpts] rangeNoiseStd has no effect: only "
                           "sensorModel = rangeNoise uses it (sensorModel is beam)";
  const auto first = noise.find(want);
  EXPECT_NE(first, std::string::npos) << noise;
  EXPECT_EQ(noise.find(want, first + 1), std::string::npos) << "told twice: " << noise;
  // The same keys where they act: nothing said.
  EXPECT_EQ(warnings(oneMap("rtreeGridMap2D", "insertOpts",
                            "sensorModelPreset=octomap\nsensorModel=rangeNoise\nrangeNoiseStd=0.02\nclampingMin=0.2\n"
                            "useMapAltitude=1\nmapAltitude=0.3")),
            "");
  const std::string grid = warnings(oneMap("rtreeGridMap2D", "insertOpts", "clampingMin=0.2\nmapAltitude=0.3"));
  EXPECT_NE(grid.find("] clampingMin has no effect: the mrpt_grid preset"), std::string::npos) << grid;
  EXPECT_NE(grid.find("] mapAltitude has no effect: only useMapAltitude = true uses it"), std::string::npos) << grid;
  const std::string prior = warnings(oneMap("rtreeOccupancyGrid", "creationOpts", "priorConfidence=0.9"));
  EXPECT_NE(prior.find("_creationOpts] priorConfidence has no effect: no priorMap is set"), std::string::npos) << prior;
}

// The sections the project ships, and every occupancy grid section of MRPT's stock configs
// pasted as either map type, still load: their booleans are true/false/1/0, their numbers plain.
// (The stock grid's widening beams, which the mrpt_grid preset does not reproduce, are refused
// by name as before.)
TEST(MapOptions, ShippedAndStockSectionsStillLoad) {
  const auto text = [](const std::string& path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  };
  const auto load = [](const std::string& body, const std::string& name) {
    mrpt::config::CConfigFileMemory c(body);
    std::vector<std::string> sections;
    c.getAllSections(sections);
    int maps = 0;
    for (const std::string& sec : sections)
      for (const char* type : {"rtreeOccupancyGrid_count", "rtreeGridMap2D_count"})
        if (c.read_int(sec, type, 0) > 0) {
          SCOPED_TRACE(name + " [" + sec + "]");
          try {
            mrpt::maps::TSetOfMetricMapInitializers inits;
            inits.loadFromConfigFile(c, sec);
            mrpt::maps::CMultiMetricMap mm;
            mm.setListOfMaps(inits);
            ++maps;
          } catch (const mrpt::ExceptionWithCallBackBase& e) {
            EXPECT_NE(e.originalWhat.find("wideningBeamsWithDistance"), std::string::npos) << e.originalWhat;
          }
        }
    return maps;
  };
  int shipped = 0;
  testing::internal::CaptureStderr();
  for (const char* f : {"icp-slam_rtog.ini", "icp-slam_rtog_gridmatch.ini", "observations2map_rtog.ini",
                        "pf-localization_rtog.ini", "pf-localization_rtog_grid2d.ini", "rbpf-slam_rtog.ini",
                        "rbpf-slam_rtog_grid2d.ini", "rtog_build.ini"})
    shipped += load(text(std::string(RTOG_CONFIG_DIR) + "/" + f), f);
  const std::string told = testing::internal::GetCapturedStderr();
  EXPECT_EQ(told.find("has no effect"), std::string::npos) << "a shipped key without effect: " << told;
  EXPECT_GE(shipped, 8);
  int stock = 0;
  const std::string list = ::testing::TempDir() + "/rtog_stock_grid_configs.txt";
  ASSERT_EQ(std::system(("grep -rl --include=*.ini occupancyGrid_count /usr/share/mrpt/config_files > " + list).c_str()), 0);
  std::istringstream files(text(list));
  testing::internal::CaptureStderr();  // the keys these sections hold and rtog ignores
  for (std::string path; std::getline(files, path);) {
    try {  // a config whose other maps MRPT 2.5 itself cannot make (its gas grids) is not ours
      mrpt::config::CConfigFileMemory c(text(path));
      std::vector<std::string> sections;
      c.getAllSections(sections);
      for (const std::string& sec : sections)
        if (c.read_int(sec, "occupancyGrid_count", 0) > 0) {
          mrpt::maps::TSetOfMetricMapInitializers inits;
          inits.loadFromConfigFile(c, sec);
          mrpt::maps::CMultiMetricMap().setListOfMaps(inits);
        }
    } catch (const std::exception&) {
      continue;
    }
    for (const std::string type : {"rtreeOccupancyGrid", "rtreeGridMap2D"}) {
      std::string body = text(path);
      for (const auto& [from, to] : {std::pair<std::string, std::string>{"occupancyGrid_count", type + "_count"},
                                     {"_occupancyGrid_", "_" + type + "_"}})
        for (std::size_t p = 0; (p = body.find(from, p)) != std::string::npos; p += to.size()) body.replace(p, from.size(), to);
      stock += load(body, path + " as " + type);
    }
  }
  testing::internal::GetCapturedStderr();
  std::remove(list.c_str());
  EXPECT_GE(stock, 16);
  std::printf("shipped sections loaded: %d, stock grid sections loaded: %d\n", shipped, stock);
}

// maxScanCells (InsertParams::max_scan_cells) goes to the core as given, survives a save and a
// load whole (MRPT writes doubles with "%e", six digits), and is refused unless a whole number.
TEST(MapOptions, MaxScanCellsReachesTheCoreAndRoundTrips) {
  rtog::CRTreeOccupancyGridMap::TInsertionOptions io;
  EXPECT_EQ(io.toInsertParams().max_scan_cells, std::uint64_t{1} << 30);
  mrpt::config::CConfigFileMemory in("[s]\nmaxScanCells = 123456789\n");
  io.loadFromConfigFile(in, "s");
  EXPECT_EQ(io.toInsertParams().max_scan_cells, 123456789u);
  mrpt::config::CConfigFileMemory out;
  io.saveToConfigFile(out, "s");
  rtog::CRTreeOccupancyGridMap::TInsertionOptions back;
  back.loadFromConfigFile(out, "s");
  EXPECT_EQ(back.toInsertParams().max_scan_cells, 123456789u);
  for (const std::string bad : {"-1", "1.5", "nan", "1e30"}) {
    mrpt::config::CConfigFileMemory c("[s]\nmaxScanCells = " + bad + "\n");
    rtog::CRTreeOccupancyGridMap::TInsertionOptions o;
    try {
      o.loadFromConfigFile(c, "s");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("maxScanCells"), std::string::npos) << e.what();
    }
  }
}
