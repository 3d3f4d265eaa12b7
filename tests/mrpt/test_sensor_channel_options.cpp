// The sensor stated by missRate / falseAlarmRate in _insertOpts: rates equivalent to a pasted
// grid section's certainties give that section's options and map bit for bit, in both presets;
// half-stated or doubly stated sensors are refused naming the keys.
#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/io/CMemoryStream.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

using rtog::CRTreeOccupancyGridMap;
using rtog_test::mapFromIni;

namespace {

std::string rates(const rtog::SensorChannel& c) {
  std::ostringstream s;
  s.precision(17);
  s << "missRate=" << c.miss_rate << "\nfalseAlarmRate=" << c.false_alarm_rate << "\n";
  return s.str();
}

std::string serialized(const CRTreeOccupancyGridMap& m) {
  mrpt::io::CMemoryStream buf;
  auto out = mrpt::serialization::archiveFrom(buf);
  out << m;
  return std::string(static_cast<const char*>(buf.getRawBufferData()), buf.getTotalBytesCount());
}

TEST(SensorChannelOptions, EquivalentRatesGiveTheCertaintiesSectionsMapOnSena) {
  const auto frames = rtog_test::loadOdometryFrames(rtog_test::dataset(rtog_test::kSena), 80);
  ASSERT_EQ(frames.size(), 80u);
  for (const std::string preset : {"mrpt_grid", "octomap"}) {
    const std::string common = "sensorModelPreset=" + preset + "\n";
    const std::string plain_opts = common + "maxOccupancyUpdateCertainty=0.65\nmaxFreenessUpdateCertainty=0.55\n";
    const auto plain = mapFromIni(plain_opts);
    rtog::LogOddsParams p;
    p.prob_hit = plain->insertionOptions.maxOccupancyUpdateCertainty;
    p.prob_miss = 1.0 - double(plain->insertionOptions.maxFreenessUpdateCertainty);
    const auto channel = mapFromIni(common + rates(rtog::channelOf(p)));
    EXPECT_EQ(channel->insertionOptions.maxOccupancyUpdateCertainty, plain->insertionOptions.maxOccupancyUpdateCertainty);
    EXPECT_EQ(channel->insertionOptions.maxFreenessUpdateCertainty, plain->insertionOptions.maxFreenessUpdateCertainty);
    for (const auto& f : frames) {
      plain->insertObservation(*f.sf->getObservationByIndex(0), f.pose);
      channel->insertObservation(*f.sf->getObservationByIndex(0), f.pose);
    }
    EXPECT_GT(plain->map().leafCount(), 1000u) << preset;
    EXPECT_EQ(serialized(*channel), serialized(*plain)) << preset;
  }
}

TEST(SensorChannelOptions, TheRatesStateAStrongerOrWeakerSensor) {
  // A sensor that seldom misses and seldom lies: larger steps both ways than OctoMap's defaults.
  const auto sure = mapFromIni("sensorModelPreset=octomap\nmissRate=0.05\nfalseAlarmRate=0.05\n");
  EXPECT_NEAR(sure->insertionOptions.maxOccupancyUpdateCertainty, 0.95f, 1e-6f);
  EXPECT_NEAR(sure->insertionOptions.maxFreenessUpdateCertainty, 0.95f, 1e-6f);
  std::ostringstream saved;
  mrpt::config::CConfigFileMemory out;
  sure->insertionOptions.saveToConfigFile(out, "s");
  EXPECT_NEAR(out.read_float("s", "missRate", 0), 0.05f, 1e-7f);
  EXPECT_FALSE(out.keyExists("s", "maxOccupancyUpdateCertainty"));  // written as it was stated
}

TEST(SensorChannelOptions, HalfOrDoublyStatedSensorsAreRefusedByKey) {
  const auto refused = [](const std::string& opts, const std::string& word) {
    try {
      mapFromIni(opts);
      ADD_FAILURE() << "accepted: " << opts;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("insertOpts"), std::string::npos) << e.what();
    }
  };
  refused("missRate=0.1\n", "falseAlarmRate");
  refused("missRate=0.1\nfalseAlarmRate=0.1\nmaxOccupancyUpdateCertainty=0.7\n", "maxOccupancyUpdateCertainty is set");
  refused("missRate=0.6\nfalseAlarmRate=0.5\n", "below 1");
  refused("missRate=nan\nfalseAlarmRate=0.1\n", "missRate");
  refused("missRate=-0.1\nfalseAlarmRate=0.1\n", "missRate");
}

}  // namespace
