// `rtog explore` as a user runs it, on the first part of SENA: the JSON holds the frontier regions
// and the views ranked by score, the picture decodes; the regions are where the rest of the log
// later observes new cells (the figure printed); bad requests are one error line, a non-zero exit
// and no output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_helpers.hpp"
#include "commands.hpp"
#include "rtog/core/band.hpp"
#include "rtog/core/explore.hpp"

namespace {
using rtog_cli_test::entries;
using rtog_cli_test::run;
using rtog_cli_test::scratch;

const std::string kSena = "\"" + std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog\"";
const std::string kOptions = " --band -0.5 1.0 --radius 0.2 --min-region 20 --max-range 6";

/// Whether column (x, y) of the band holds a known cell.
bool knownColumn(const rtog::OccupancyMap& m, std::int32_t x, std::int32_t y) {
  const rtog::Box r = rtog::bandRegion(m, rtog::Box{rtog::Key{x, y, 0}, rtog::Key{x, y, 0}}, -0.5, 1.0);
  bool known = false;
  if (!r.isEmpty()) m.forEachLeafIn(r, [&](const rtog::Box&, float) { known = true; });
  return known;
}
}  // namespace

TEST(CliExplore, RegionsAndRankedViewsWhereTheRestOfTheLogLooks) {
  const std::string d = scratch("explore");
  std::string out;
  ASSERT_EQ(run("build --rawlog " + kSena + " --scans 0:110 --resolution 0.05 --max-range 15 --out " + d + "/half.rtog", &out), 0) << out;
  ASSERT_EQ(run("build --rawlog " + kSena + " --resolution 0.05 --max-range 15 --out " + d + "/all.rtog", &out), 0) << out;
  ASSERT_EQ(run("explore " + d + "/half.rtog --from 0 0" + kOptions + " --out " + d + "/views.json --png " + d + "/views.png", &out), 0)
      << out;
  EXPECT_NE(out.find("frontier regions (band)"), std::string::npos) << out;
  std::ifstream in(d + "/views.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_GE(j["regions"].size(), 5u);
  ASSERT_GE(j["views"].size(), 3u);
  EXPECT_TRUE(j["views"][0]["reachable"].get<bool>());
  for (std::size_t i = 1; i < j["views"].size(); ++i)
    EXPECT_LE(j["views"][i]["score"].get<double>(), j["views"][i - 1]["score"].get<double>());
  for (std::size_t i = 1; i < j["regions"].size(); ++i)
    EXPECT_LE(j["regions"][i]["cells"].get<long long>(), j["regions"][i - 1]["cells"].get<long long>());
  EXPECT_FALSE(cv::imread(d + "/views.png").empty());

  // The largest regions' frontier columns: how many see an unknown neighbour column of the first
  // part become known in the whole log.
  const rtog::OccupancyMap half = rtog::cli::loadMap(d + "/half.rtog"), all = rtog::cli::loadMap(d + "/all.rtog");
  rtog::FrontierOptions fo;
  fo.planar = true, fo.min_z = -0.5, fo.max_z = 1.0, fo.min_region_cells = 20;
  const auto regions = rtog::frontierRegions(half, fo);
  ASSERT_EQ(regions.size(), j["regions"].size());
  int realised = 0;
  for (std::size_t r = 0; r < 5; ++r) {
    std::size_t columns = 0, seen = 0;
    for (const rtog::Box& b : regions[r].boxes)
      for (std::int32_t x = b.min.x; x <= b.max.x; ++x) {
        ++columns;
        bool later = false;
        for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
          later = later || (!knownColumn(half, x + dx, b.min.y + dy) && knownColumn(all, x + dx, b.min.y + dy));
        seen += later;
      }
    std::printf("region %zu: %lld columns at (%.1f, %.1f); %.0f %% of them see new columns in the whole log\n", r,
                static_cast<long long>(regions[r].cells), regions[r].centroid.x(), regions[r].centroid.y(),
                100.0 * double(seen) / double(columns));
    realised += 2 * seen > columns;
  }
  EXPECT_GE(realised, 3);
}

TEST(CliExplore, BadRequestsAreOneErrorLineAndNoOutput) {
  const std::string d = scratch("explore_bad");
  std::string out;
  ASSERT_EQ(run("build --rawlog " + kSena + " --scans 0:20 --resolution 0.1 --out " + d + "/m.rtog", &out), 0) << out;
  EXPECT_NE(run("explore " + d + "/m.rtog --from 0 0 0 --band 0 1 --out " + d + "/v.json", &out), 0);
  EXPECT_NE(out.find("--band is for 2D"), std::string::npos) << out;
  EXPECT_NE(run("explore " + d + "/m.rtog --from 0 0 --sensor sonar --out " + d + "/v.json", &out), 0);
  EXPECT_NE(run("explore " + d + "/m.rtog --from 0 0 --standoff 0 --out " + d + "/v.json", &out), 0);
  EXPECT_NE(run("explore " + d + "/missing.rtog --from 0 0 --out " + d + "/v.json", &out), 0);
  EXPECT_EQ(entries(d), std::vector<std::string>{"m.rtog"});
}
