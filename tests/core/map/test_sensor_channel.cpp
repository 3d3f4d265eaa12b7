// The sensor stated as a miss / false-alarm channel: its log-odds changes follow Bayes' rule,
// and rates equivalent to given hit and miss probabilities give the plain update bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <vector>

#include "rtog/core/occupancy_map.hpp"
#include "test_support.hpp"

using namespace rtog;

namespace {

TEST(SensorChannel, UpdatesAreTheChannelsLikelihoodRatios) {
  const SensorChannel c{0.1, 0.05};
  const LogOddsModel m(withChannel(LogOddsParams{}, c));
  // P(detection | occ) / P(detection | free) and P(none | occ) / P(none | free).
  EXPECT_NEAR(m.hitDelta(), std::log(0.9 / 0.05), 1e-6);
  EXPECT_NEAR(m.missDelta(), std::log(0.1 / 0.95), 1e-6);
  // With another prior the changes stay the channel's: l_meas - l0.
  LogOddsParams p;
  p.prior = 0.3;
  p.clamp_min = 0.1;
  const LogOddsModel q(withChannel(p, c));
  EXPECT_NEAR(q.hitDelta(), std::log(0.9 / 0.05), 1e-6);
  EXPECT_NEAR(q.missDelta(), std::log(0.1 / 0.95), 1e-6);
  // The default channel is the default parameters'.
  const SensorChannel d = channelOf(LogOddsParams{});
  EXPECT_NEAR(d.miss_rate, SensorChannel{}.miss_rate, 1e-12);
  EXPECT_NEAR(d.false_alarm_rate, SensorChannel{}.false_alarm_rate, 1e-12);
}

TEST(SensorChannel, EquivalentRatesGiveTheSameFloatUpdates) {
  std::size_t pairs = 0;
  for (const double prior : {0.5, 0.3, 0.62})
    for (double hit = prior + 0.02; hit < 0.99; hit += 0.037)
      for (double miss = 0.02; miss < prior - 0.01; miss += 0.029) {
        LogOddsParams p;
        p.prior = prior;
        p.prob_hit = hit;
        p.prob_miss = miss;
        p.clamp_min = 0.01;
        p.clamp_max = 0.995;
        const LogOddsModel plain(p), channel(withChannel(p, channelOf(p)));
        ASSERT_EQ(plain.hitDelta(), channel.hitDelta()) << "prior " << prior << " hit " << hit << " miss " << miss;
        ASSERT_EQ(plain.missDelta(), channel.missDelta()) << "prior " << prior << " hit " << hit << " miss " << miss;
        ++pairs;
      }
  EXPECT_GT(pairs, 300u);
}

// On the bundled Kinect frames: the map of the default parameters and the map of their channel
// hold the same leaves with the same values.
TEST(SensorChannel, EquivalentRatesBuildTheSameMapOnRealFrames) {
  MapParams plain;
  plain.merge = MergePolicy::Equal;
  MapParams channel = plain;
  channel.log_odds = withChannel(plain.log_odds, channelOf(plain.log_odds));
  OccupancyMap a(plain), b(channel);
  InsertParams ip;
  ip.discretize = true;
  for (const auto& s : test::loadTumScans(4)) {
    const InsertStats sa = a.insertPointCloud(s.origin, s.points, ip), sb = b.insertPointCloud(s.origin, s.points, ip);
    ASSERT_EQ(sa, sb);
  }
  std::vector<std::pair<Box, float>> la, lb;
  a.forEachLeaf([&](const Box& box, float v) { la.push_back({box, v}); });
  b.forEachLeaf([&](const Box& box, float v) { lb.push_back({box, v}); });
  ASSERT_EQ(la.size(), lb.size());
  EXPECT_GT(la.size(), 10000u);
  for (std::size_t i = 0; i < la.size(); ++i) {
    ASSERT_EQ(la[i].first, lb[i].first);
    ASSERT_EQ(std::memcmp(&la[i].second, &lb[i].second, sizeof(float)), 0);
  }
}

TEST(SensorChannel, BadRatesAreRefusedByName) {
  const auto refused = [](double m, double f, const char* what) {
    try {
      withChannel(LogOddsParams{}, SensorChannel{m, f});
      ADD_FAILURE() << "accepted " << m << ", " << f;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused(0.0, 0.2, "miss_rate");
  refused(0.3, 1.0, "false_alarm_rate");
  refused(std::nan(""), 0.2, "miss_rate");
  refused(0.6, 0.5, "below 1");
}

}  // namespace
