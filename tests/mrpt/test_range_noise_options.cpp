// sensorModel = rangeNoise in _insertOpts: sigma 0 gives the beam model's map on SENA cell for
// cell, a real sigma changes it; the options read, write and serialize back; bad values are
// refused naming the key; rangeNoiseSharedBand acts where the core walks the beams.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "map_cells.hpp"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using rtog_test::mapFromIni;
using rtog::test::cellsOf;

namespace {

TEST(RangeNoiseOptions, ZeroSigmaGivesTheBeamModelsMapOnSena) {
  const auto frames = rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 80);
  ASSERT_EQ(frames.size(), 80u);
  const std::string common = "sensorModelPreset=octomap\n";
  const auto beam = mapFromIni(common + "sensorModel=beam\n");
  const auto zero = mapFromIni(common + "sensorModel=rangeNoise\nrangeNoiseStd=0\n");
  const auto noisy = mapFromIni(common + "sensorModel=rangeNoise\nrangeNoiseStd=0.03\nrangeNoiseStdPerMeter=0.01\n");
  for (const auto& f : frames)
    for (const auto& m : {beam, zero, noisy}) m->insertObservation(*f.sf->getObservationByIndex(0), f.pose);
  const auto a = cellsOf(beam->map()), b = cellsOf(zero->map()), c = cellsOf(noisy->map());
  ASSERT_GT(a.size(), 100000u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first);
    ASSERT_EQ(std::memcmp(&a[i].second, &b[i].second, sizeof(float)), 0) << "cell " << i;
  }
  EXPECT_NE(a, c);
  EXPECT_EQ(noisy->map().checkInvariants(), "");
  EXPECT_GT(noisy->lastInsertStats.cells_occupied, beam->lastInsertStats.cells_occupied)
      << "the band marks more cells than the end cells";
}

TEST(RangeNoiseOptions, OptionsReadWriteAndSerializeBack) {
  const auto m = mapFromIni("sensorModelPreset=octomap\nsensorModel=rangeNoise\nrangeNoiseStd=0.02\n"
                            "rangeNoiseStdPerMeter=0.005\nrangeNoiseCutoff=2.5\nrangeNoiseSharedBand=7\n");
  const auto& io = m->insertionOptions;
  EXPECT_EQ(io.sensorModel, "rangeNoise");
  EXPECT_FLOAT_EQ(io.rangeNoiseStd, 0.02f);
  EXPECT_FLOAT_EQ(io.rangeNoiseStdPerMeter, 0.005f);
  EXPECT_FLOAT_EQ(io.rangeNoiseCutoff, 2.5f);
  EXPECT_EQ(io.rangeNoiseSharedBand, 7);
  EXPECT_EQ(io.toInsertParams().range_noise_shared_band, 7u);
  mrpt::config::CConfigFileMemory out;
  io.saveToConfigFile(out, "s");
  CRTreeOccupancyGridMap::TInsertionOptions again;
  again.loadFromConfigFile(out, "s");
  EXPECT_EQ(again.rangeNoiseStd, io.rangeNoiseStd);
  EXPECT_EQ(again.rangeNoiseCutoff, io.rangeNoiseCutoff);
  EXPECT_EQ(again.rangeNoiseSharedBand, 7);
  mrpt::io::CMemoryStream buf;
  auto arch = mrpt::serialization::archiveFrom(buf);
  arch << *m;
  buf.Seek(0);
  CRTreeOccupancyGridMap back;
  arch >> back;
  EXPECT_EQ(back.insertionOptions.sensorModel, "rangeNoise");
  EXPECT_EQ(back.insertionOptions.rangeNoiseStdPerMeter, io.rangeNoiseStdPerMeter);
  EXPECT_EQ(back.insertionOptions.rangeNoiseCutoff, io.rangeNoiseCutoff);
  EXPECT_EQ(back.insertionOptions.rangeNoiseSharedBand, 7);
}

// rangeNoiseSharedBand acts wherever the core walks the beams: a depth image in either preset
// (a 2D mrpt_grid section takes 3D observations by the core's walk); on the 2D grid's own raster
// (SENA's scans in mrpt_grid) every beam keeps its band, so the key changes nothing there.
TEST(RangeNoiseOptions, TheSharedBandActsWhereTheCoreWalksTheBeams) {
  const auto rgbd = rtog_test::firstObservation(rtog_test::dataset("tests_rgbd.rawlog"));
  const std::string noise = "sensorModel=rangeNoise\nrangeNoiseStd=0.02\nrangeNoiseStdPerMeter=0.01\n";
  for (const std::string preset : {"", "sensorModelPreset=octomap\n"}) {
    const auto shared = mapFromIni(preset + noise), apart = mapFromIni(preset + noise + "rangeNoiseSharedBand=0\n");
    for (const auto& m : {shared, apart}) {
      ASSERT_TRUE(m->insertObservation(*rgbd, mrpt::poses::CPose3D()));
      EXPECT_EQ(m->map().checkInvariants(), "");
    }
    const auto a = cellsOf(shared->map()), b = cellsOf(apart->map());
    ASSERT_GT(a.size(), 1000u) << preset;
    EXPECT_NE(a, b) << "the depth image's beams share bands (" << preset << ")";
  }
  const auto frames = rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 40);
  const auto shared = mapFromIni(noise), apart = mapFromIni(noise + "rangeNoiseSharedBand=0\n");
  for (const auto& f : frames)
    for (const auto& m : {shared, apart}) m->insertObservation(*f.sf->getObservationByIndex(0), f.pose);
  EXPECT_EQ(cellsOf(shared->map()), cellsOf(apart->map())) << "mrpt_grid grades a 2D scan's beams on its raster";
}

// Range noise in both presets (in mrpt_grid on the grid's raster and int8 lattice,
// test_mrpt_grid_estimator.cpp); bad values refused by key in either.
TEST(RangeNoiseOptions, BadValuesAreRefusedByKeyInBothPresets) {
  const auto refused = [](const std::string& opts, const std::string& key) {
    try {
      mapFromIni(opts);
      ADD_FAILURE() << "accepted: " << opts;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("insertOpts"), std::string::npos) << e.what();
    }
  };
  for (const std::string preset : {"", "sensorModelPreset=octomap\n"}) {  // mrpt_grid is the default preset
    const std::string o = preset + "sensorModel=rangeNoise\n";
    auto m = mapFromIni(o);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->insertionOptions.sensorModel, "rangeNoise");
    refused(o + "rangeNoiseStd=-0.01\n", "rangeNoiseStd");
    refused(o + "rangeNoiseStd=nan\n", "rangeNoiseStd");
    refused(o + "rangeNoiseStdPerMeter=inf\n", "rangeNoiseStdPerMeter");
    refused(o + "rangeNoiseCutoff=20\n", "rangeNoiseCutoff");
    refused(o + "rangeNoiseCutoff=0\n", "rangeNoiseCutoff");
    refused(o + "rangeNoiseSharedBand=-1\n", "rangeNoiseSharedBand");
  }
}

}  // namespace
