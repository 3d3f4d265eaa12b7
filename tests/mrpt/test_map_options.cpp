// .ini -> CMultiMetricMap creates our maps with the given options; bad values fail clearly.
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

const char* kIni = R"(
[MappingApplication]
rtreeOccupancyGrid_count=1
occupancyGrid_count=1

[MappingApplication_rtreeOccupancyGrid_00_creationOpts]
resolution=0.2

[MappingApplication_rtreeOccupancyGrid_00_insertOpts]
sensorModelPreset=octomap
sensorModel=endpoint
maxOccupancyUpdateCertainty=0.8
maxFreenessUpdateCertainty=0.6
clampingMin=0.2
clampingMax=0.9
maxDistanceInsertion=12.5
decimation=3
decimation_3d_range=4
mergePolicy=equal

[MappingApplication_rtreeOccupancyGrid_00_likelihoodOpts]
likelihoodMethod=lmRayTracing
LF_stdHit=0.2
LF_decimation=7
rayTracing_stdHit=0.5
enableLikelihoodCache=false
)";

}  // namespace

TEST(MapOptions, IniCreatesMapWithOptions) {
  auto mm = fromIni(kIni);
  ASSERT_EQ(mm.maps.size(), 2u);
  auto m = mm.mapByClass<CRTreeOccupancyGridMap>();
  ASSERT_TRUE(m);
  EXPECT_DOUBLE_EQ(m->resolution(), 0.2);
  EXPECT_EQ(m->insertionOptions.sensorModel, "endpoint");
  EXPECT_FLOAT_EQ(m->insertionOptions.maxOccupancyUpdateCertainty, 0.8f);
  EXPECT_FLOAT_EQ(m->insertionOptions.maxDistanceInsertion, 12.5f);
  EXPECT_EQ(m->insertionOptions.decimation, 3);
  EXPECT_EQ(m->insertionOptions.decimation_3d_range, 4);
  EXPECT_EQ(m->insertionOptions.mergePolicy, "equal");
  EXPECT_EQ(m->likelihoodOptions.likelihoodMethod, CRTreeOccupancyGridMap::lmRayTracing);
  EXPECT_FLOAT_EQ(m->likelihoodOptions.LF_stdHit, 0.2f);
  EXPECT_EQ(m->likelihoodOptions.LF_decimation, 7u);
  EXPECT_FLOAT_EQ(m->likelihoodOptions.rayTracing_stdHit, 0.5f);
  EXPECT_FALSE(m->likelihoodOptions.enableLikelihoodCache);
  // The options reach the core map.
  const auto& p = m->map().params();
  EXPECT_NEAR(p.log_odds.prob_hit, 0.8, 1e-6);
  EXPECT_NEAR(p.log_odds.prob_miss, 0.4, 1e-6);
  EXPECT_NEAR(p.log_odds.clamp_min, 0.2, 1e-6);
  EXPECT_NEAR(p.log_odds.clamp_max, 0.9, 1e-6);
  EXPECT_EQ(p.merge, rtog::MergePolicy::Equal);
  // The stock grid is still there and untouched.
  EXPECT_TRUE(mm.mapByClass<mrpt::maps::COccupancyGridMap2D>());
}

TEST(MapOptions, DefaultsMatchStockGridWhereShared) {
  CRTreeOccupancyGridMap m;
  mrpt::maps::COccupancyGridMap2D g;
  EXPECT_FLOAT_EQ(m.insertionOptions.maxOccupancyUpdateCertainty, g.insertionOptions.maxOccupancyUpdateCertainty);
  EXPECT_FLOAT_EQ(m.insertionOptions.maxFreenessUpdateCertainty, g.insertionOptions.maxFreenessUpdateCertainty);
  EXPECT_FLOAT_EQ(m.insertionOptions.maxDistanceInsertion, g.insertionOptions.maxDistanceInsertion);
  EXPECT_EQ(m.insertionOptions.decimation, g.insertionOptions.decimation);
  EXPECT_FLOAT_EQ(m.likelihoodOptions.LF_stdHit, g.likelihoodOptions.LF_stdHit);
  EXPECT_FLOAT_EQ(m.likelihoodOptions.LF_zHit, g.likelihoodOptions.LF_zHit);
  EXPECT_FLOAT_EQ(m.likelihoodOptions.LF_zRandom, g.likelihoodOptions.LF_zRandom);
  EXPECT_FLOAT_EQ(m.likelihoodOptions.LF_maxRange, g.likelihoodOptions.LF_maxRange);
  EXPECT_EQ(m.likelihoodOptions.LF_decimation, g.likelihoodOptions.LF_decimation);
  EXPECT_FLOAT_EQ(m.likelihoodOptions.LF_maxCorrsDistance, g.likelihoodOptions.LF_maxCorrsDistance);
  EXPECT_EQ(m.likelihoodOptions.rayTracing_decimation, g.likelihoodOptions.rayTracing_decimation);
  EXPECT_FLOAT_EQ(m.likelihoodOptions.rayTracing_stdHit, g.likelihoodOptions.rayTracing_stdHit);
  EXPECT_DOUBLE_EQ(m.resolution(), 0.10);
}

TEST(MapOptions, BadValuesThrowClearly) {
  auto check = [&](const std::string& section, const std::string& kv, const std::string& word) {
    const std::string ini = "[MappingApplication]\nrtreeOccupancyGrid_count=1\n[MappingApplication_rtreeOccupancyGrid_00_" +
                            section + "]\n" + kv + "\n";
    try {
      fromIni(ini);
      ADD_FAILURE() << "no exception for " << kv;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  check("creationOpts", "resolution=-0.1", "resolution");
  check("creationOpts", "resolution=0", "resolution");
  check("insertOpts", "sensorModel=laser", "sensor model");
  check("insertOpts", "mergePolicy=sometimes", "merge policy");
  check("insertOpts", "maxOccupancyUpdateCertainty=1.5", "maxOccupancyUpdateCertainty");
  check("insertOpts", "decimation=0", "decimation");
  check("insertOpts", "clampingMin=0.95", "clamp");
  check("likelihoodOpts", "likelihoodMethod=lmMagic", "likelihoodMethod");
  check("likelihoodOpts", "LF_stdHit=-1", "LF_stdHit");
}

TEST(MapOptions, BackedGridIsAnOccupancyGridMap2D) {
  auto mm = fromIni(R"(
[MappingApplication]
rtreeGridMap2D_count=1
[MappingApplication_rtreeGridMap2D_00_creationOpts]
resolution=0.05
[MappingApplication_rtreeGridMap2D_00_likelihoodOpts]
LF_decimation=9
)");
  auto g = mm.mapByClass<mrpt::maps::COccupancyGridMap2D>();
  ASSERT_TRUE(g);
  auto b = std::dynamic_pointer_cast<rtog::CRTreeBackedGridMap2D>(g);
  ASSERT_TRUE(b);
  EXPECT_FLOAT_EQ(g->getResolution(), 0.05f);
  EXPECT_DOUBLE_EQ(b->rtreeMap().resolution(), 0.05);
  EXPECT_EQ(g->likelihoodOptions.LF_decimation, 9u);
}

// The backed grid's likelihood options are COccupancyGridMap2D's, which MRPT reads unchecked: a
// beam step of 0 (here as rtog_fuzz_ini found it, "LF_decimation==") made its likelihood field
// loop forever. Each such value is now a clear error at creation, as for the R-tree map (MRPT's
// reader takes no rayTracing_decimation from an .ini: HostileFiles covers it in a stored map).
TEST(MapOptions, BackedGridLikelihoodValuesAreChecked) {
  for (const auto& [line, key] : std::vector<std::pair<std::string, std::string>>{
           {"LF_decimation==", "LF_decimation"},
           {"LF_decimation=0", "LF_decimation"},
           {"MI_skip_rays=0", "MI_skip_rays"},
           {"consensus_takeEachRange=0", "consensus_takeEachRange"},
           {"LF_stdHit=0", "LF_stdHit"},
           {"LF_maxRange=nan", "LF_maxRange"}}) {
    SCOPED_TRACE(line);
    try {
      fromIni("[MappingApplication]\nrtreeGridMap2D_count=1\n[MappingApplication_rtreeGridMap2D_00_likelihoodOpts]\n" +
              line + "\n");
      ADD_FAILURE() << "no exception";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("rtog::CRTreeBackedGridMap2D"), std::string::npos) << e.what();
    }
  }
}

TEST(MapOptions, SaveToConfigFileRoundTrip) {
  CRTreeOccupancyGridMap::TInsertionOptions io;
  io.sensorModel = "endpoint";
  io.maxDistanceInsertion = 7.5f;
  io.mergePolicy = "off";
  io.discretize = true;
  io.planarCache = false;
  CRTreeOccupancyGridMap::TLikelihoodOptions lo;
  lo.likelihoodMethod = CRTreeOccupancyGridMap::lmRayTracing;
  lo.LF_maxCorrsDistance = 0.7f;
  mrpt::config::CConfigFileMemory cfg;
  io.saveToConfigFile(cfg, "ins");
  lo.saveToConfigFile(cfg, "lik");
  CRTreeOccupancyGridMap::TInsertionOptions io2;
  CRTreeOccupancyGridMap::TLikelihoodOptions lo2;
  io2.loadFromConfigFile(cfg, "ins");
  lo2.loadFromConfigFile(cfg, "lik");
  EXPECT_EQ(io2.sensorModel, "endpoint");
  EXPECT_FLOAT_EQ(io2.maxDistanceInsertion, 7.5f);
  EXPECT_EQ(io2.mergePolicy, "off");
  EXPECT_TRUE(io2.discretize);
  EXPECT_FALSE(io2.planarCache);
  EXPECT_EQ(lo2.likelihoodMethod, CRTreeOccupancyGridMap::lmRayTracing);
  EXPECT_FLOAT_EQ(lo2.LF_maxCorrsDistance, 0.7f);
}

TEST(MapOptions, ChangingProbabilitiesOfANonEmptyMapThrows) {
  CRTreeOccupancyGridMap m(0.1);
  mrpt::obs::CObservation2DRangeScan scan;
  scan.resizeScan(3);
  for (std::size_t i = 0; i < 3; ++i) {
    scan.setScanRange(i, 2.0f);
    scan.setScanRangeValidity(i, true);
  }
  EXPECT_TRUE(m.insertObservation(scan));
  m.insertionOptions.maxOccupancyUpdateCertainty = 0.9f;
  EXPECT_THROW(m.insertObservation(scan), std::logic_error);
  m.clear();
  EXPECT_TRUE(m.insertObservation(scan));
  // mrpt_grid: P = 0.9 is the int8 step p2l(0.9) = 35, three times for a hit: 105 / 16.
  EXPECT_EQ(static_cast<float>(rtog::logit(m.map().params().log_odds.prob_hit)), 105.0f / 16.0f);
  m.insertionOptions.sensorModelPreset = "octomap";
  EXPECT_THROW(m.insertObservation(scan), std::logic_error);
  m.clear();
  EXPECT_TRUE(m.insertObservation(scan));
  EXPECT_NEAR(m.map().params().log_odds.prob_hit, 0.9, 1e-6);
}

TEST(MapOptions, MrptGridStepsAreTheGridsInt8Steps) {
  // icp-slam_demo_classic_gridmatch.ini's 0.54: p2l gives 2, so free steps of 2 and occupied of 6.
  CRTreeOccupancyGridMap::TInsertionOptions io;
  io.maxOccupancyUpdateCertainty = 0.54f;
  CRTreeOccupancyGridMap m(0.05, io);
  const rtog::LogOddsModel& lm = m.map().logOddsModel();
  EXPECT_EQ(lm.hitDelta(), 6.0f / 16.0f);
  EXPECT_EQ(lm.missDelta(), -2.0f / 16.0f);
  EXPECT_EQ(lm.clampMin(), -127.0f / 16.0f);
  EXPECT_EQ(lm.clampMax(), 127.0f / 16.0f);
  EXPECT_EQ(lm.prior(), 0.0f);
}

TEST(MapOptions, UnknownKeysAreReported) {
  const std::string ini =
      "[MappingApplication]\nrtreeOccupancyGrid_count=1\n[MappingApplication_rtreeOccupancyGrid_00_insertOpts]\n"
      "maxOccupancyUpdateCertainty=0.6\nmaxOcupancyUpdateCertainty=0.7\n";
  testing::internal::CaptureStderr();
  fromIni(ini);
  fromIni(ini);
  const std::string err = testing::internal::GetCapturedStderr();
  const std::string want = "unknown key 'maxOcupancyUpdateCertainty'";
  const auto first = err.find(want);
  ASSERT_NE(first, std::string::npos) << err;
  EXPECT_EQ(err.find(want, first + 1), std::string::npos) << "reported twice: " << err;
  EXPECT_EQ(err.find("'maxOccupancyUpdateCertainty'"), std::string::npos) << err;
}

// A process reading many generated sections keeps a bounded memory of what it told: after 1,000
// unknown keys, one line says that the rest go untold.
TEST(MapOptions, UnknownKeyWarningsAreBounded) {
  std::string ini = "[MappingApplication]\nrtreeOccupancyGrid_count=1\n[MappingApplication_rtreeOccupancyGrid_00_insertOpts]\n";
  for (int i = 0; i < 1500; ++i) ini += "noSuchKey" + std::to_string(i) + "=1\n";
  testing::internal::CaptureStderr();
  fromIni(ini);
  const std::string err = testing::internal::GetCapturedStderr();
  std::size_t told = 0;
  for (std::size_t p = 0; (p = err.find("unknown key 'noSuchKey", p)) != std::string::npos; ++p) ++told;
  EXPECT_LE(told, 1000u);
  EXPECT_GT(told, 0u);
  EXPECT_NE(err.find("further unknown keys are ignored without a warning"), std::string::npos);
}

// Every key of MRPT's own stock grid sections is known: pasting them warns about the one key the
// stock grid ignores as well (minLaserScanNoiseStd) and about nothing else.
TEST(MapOptions, StockGridSectionsWarnOnlyAboutKeysTheGridIgnores) {
  std::size_t warnings = 0;
  for (const char* cfg : {"icp-slam/icp-slam_demo_classic_gridmatch.ini", "rbpf-slam/gridmapping_optimal_sampling.ini",
                          "pf-localization/localization_demo.ini", "rbpf-slam/gridmapping_RBPF_grid_ICPbased_malaga.ini"}) {
    std::ifstream f(std::string("/usr/share/mrpt/config_files/") + cfg);
    ASSERT_TRUE(f) << cfg;
    std::stringstream ss;
    ss << f.rdbuf();
    std::string text = ss.str();
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"occupancyGrid_count", "rtreeOccupancyGrid_count"},
                                   {"_occupancyGrid_00_", "_rtreeOccupancyGrid_00_"}})
      for (std::size_t p = 0; (p = text.find(from, p)) != std::string::npos; p += to.size()) text.replace(p, from.size(), to);
    const std::string prefix = text.find("[MetricMap]") != std::string::npos ? "MetricMap" : "MappingApplication";
    mrpt::config::CConfigFileMemory c(text);
    mrpt::maps::TSetOfMetricMapInitializers inits;
    testing::internal::CaptureStderr();
    inits.loadFromConfigFile(c, prefix);
    const std::string err = testing::internal::GetCapturedStderr();
    std::istringstream lines(err);
    for (std::string line; std::getline(lines, line);) {
      if (line.find("unknown key") == std::string::npos) continue;
      ++warnings;
      EXPECT_NE(line.find("'minLaserScanNoiseStd'"), std::string::npos) << cfg << ": " << line;
    }
  }
  EXPECT_GE(warnings, 1u);  // the capture sees the warnings (icp-slam's section has that key)
}

TEST(MapOptions, WideningBeamsRefusedInMrptGridPreset) {
  const std::string ini =
      "[MappingApplication]\nrtreeOccupancyGrid_count=1\n[MappingApplication_rtreeOccupancyGrid_00_insertOpts]\n"
      "wideningBeamsWithDistance=true\n";
  try {
    fromIni(ini);
    ADD_FAILURE() << "no exception";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("wideningBeamsWithDistance"), std::string::npos) << e.what();
  }
}

// MRPT reads "<map>_count" unsigned: "-1" would make four billion map definitions (rtog_fuzz_ini
// ran out of memory on it). The check refuses such counts by key, before MRPT's loader runs.
TEST(MapOptions, MapCountsAreBoundedBeforeMrptReadsThem) {
  const auto counts = [](const std::string& kv) {
    mrpt::config::CConfigFileMemory cfg("[MappingApplication]\n" + kv + "\n");
    rtog::checkMapCounts(cfg, "MappingApplication");
  };
  for (const std::string bad : {"rtreeOccupancyGrid_count=-1", "occupancyGrid_count = 4294967295",
                                "RTREEOCCUPANCYGRID_COUNT=1001", "octoMap_count=lots"}) {
    try {
      counts(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::invalid_argument& e) {
      const std::string key = bad.substr(0, bad.find_first_of(" ="));
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("[MappingApplication]"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(counts("rtreeOccupancyGrid_count=2 // two maps\noccupancyGrid_count=0\nresolution=-1"));
}
