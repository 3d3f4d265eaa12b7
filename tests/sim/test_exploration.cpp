// Closed-loop exploration in simulated worlds with known truth (rtog/sim/exploration.hpp): both
// strategies explore the free space reachable from the start; the coverage never falls and the
// path never shrinks; information-gain views reach 90 % coverage in fewer metres than the nearest
// frontier on at least two of six worlds (seeds 1 to 6, not those the loop was debugged on; the
// figures printed go to doc/exploration.md).
#include <gtest/gtest.h>

#include <cstdio>

#include "rtog/sim/exploration.hpp"

using namespace rtog;
using namespace rtog::sim;

TEST(Exploration, InformationGainViewsCoverTheWorldsInFewerMetres) {
  int fewer = 0;
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    const World w = World::generate(WorldParams{}, seed);
    double metres[2] = {0, 0};
    for (const ExploreStrategy s : {ExploreStrategy::NearestFrontier, ExploreStrategy::InformationGain}) {
      const auto steps = explore(w, s, ExplorationParams::indoor());
      ASSERT_GE(steps.size(), 2u);
      for (std::size_t i = 1; i < steps.size(); ++i) {
        EXPECT_GE(steps[i].coverage, steps[i - 1].coverage);
        EXPECT_GE(steps[i].path_length, steps[i - 1].path_length);
      }
      const double m = lengthToCoverage(steps, 0.9);
      metres[s == ExploreStrategy::InformationGain] = m;
      std::printf("world %u, %s: %zu steps, %.1f m, coverage %.3f; 90 %% at %.1f m\n", seed,
                  s == ExploreStrategy::InformationGain ? "information gain" : "nearest frontier", steps.size() - 1,
                  steps.back().path_length, steps.back().coverage, m);
    }
    fewer += metres[1] > 0 && (metres[0] < 0 || metres[1] < metres[0]);
  }
  std::printf("information gain in fewer metres on %d of 6 worlds\n", fewer);
  EXPECT_GE(fewer, 2);
}
