// `rtog image` as a user runs it, on a map `rtog build` makes from Debian's SENA rawlog: the JSON's
// wall segments are the library's (houghSegments on the loaded map's band, after the same
// threshold and closing), the pictures decode, the prior image is read back by `rtog prior`, and
// bad requests are one error line, a non-zero exit and no output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <string>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_helpers.hpp"
#include "commands.hpp"
#include "rtog/image/grid_ops.hpp"

namespace {
using rtog_cli_test::entries;
using rtog_cli_test::run;
using rtog_cli_test::scratch;
const std::string kSena = std::string(RTOG_MRPT_DATASETS) + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
}  // namespace

TEST(CliImage, WallsAreTheLibrarysAndThePicturesDecode) {
  const std::string d = scratch("image");
  std::string out;
  ASSERT_EQ(run("build --rawlog '" + kSena + "' --resolution 0.05 --out " + d + "/m.rtog", &out), 0) << out;
  ASSERT_EQ(run("image " + d + "/m.rtog --band -1 2 --close 3 --hough --hough-min-length 2 --segment --out " + d +
                    "/r.json --png " + d + "/r.png --prior-png " + d + "/prior.png",
                &out),
            0)
      << out;
  nlohmann::json j;
  std::ifstream(d + "/r.json") >> j;
  const rtog::OccupancyMap m = rtog::cli::loadMap(d + "/m.rtog");
  const auto g = rtog::image::bandImage(m, -1, 2);
  const auto want = rtog::image::houghSegments(rtog::image::close(rtog::image::threshold(g, 0.5), 3), g, 2.0, 0.3);
  ASSERT_EQ(j["segments"].size(), want.size());
  ASSERT_GT(want.size(), 5u);
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_DOUBLE_EQ(j["segments"][i][0].get<double>(), want[i].a.x());
    EXPECT_DOUBLE_EQ(j["segments"][i][3].get<double>(), want[i].b.y());
  }
  EXPECT_GT(j["regions"].size(), 0u);
  EXPECT_FALSE(cv::imread(d + "/r.png").empty());
  // The prior image is the band, one pixel a cell (row 0 the highest y): grey 255 (1 - P),
  // mid-grey 128 where the band is unknown.
  const cv::Mat prior = cv::imread(d + "/prior.png", cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(prior.cols, g.p.cols);
  ASSERT_EQ(prior.rows, g.p.rows);
  std::size_t wrong_pixels = 0;
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c) {
      const float p = g.p.at<float>(r, c);
      wrong_pixels += prior.at<std::uint8_t>(r, c) != (std::isnan(p) ? 128 : std::lround(255.0 * (1.0 - p)));
    }
  EXPECT_EQ(wrong_pixels, 0u);
  // It goes back in through `rtog prior` at the origin the tool printed: the map holds one cell per
  // pixel that MRPT's own grid reads as known from the image (white free, black occupied,
  // mid-grey unknown: doc/priors.md), at that pixel's place, P(occupied) = 1 - the grid's
  // P(free) (confidence 1), in one plane, and no other cell.
  const std::string origin = std::to_string(g.x0 * g.resolution) + " " + std::to_string(g.y0 * g.resolution);
  ASSERT_EQ(run("prior --image " + d + "/prior.png --resolution 0.05 --origin " + origin + " --confidence 1 --out " + d +
                    "/p.rtog",
                &out),
            0)
      << out;
  mrpt::maps::COccupancyGridMap2D grid;
  ASSERT_TRUE(grid.loadFromBitmapFile(d + "/prior.png", 0.05f, mrpt::math::TPoint2D(-g.x0, -g.y0)));
  ASSERT_EQ(int(grid.getSizeX()), g.p.cols);
  ASSERT_EQ(int(grid.getSizeY()), g.p.rows);
  std::size_t known = 0;
  for (const auto l : grid.getRawMap()) known += l != 0;
  const rtog::OccupancyMap pm = rtog::cli::loadMap(d + "/p.rtog");
  std::size_t cells = 0, misplaced = 0, wrong_values = 0;
  std::set<std::int32_t> planes;
  pm.forEachLeaf([&](const rtog::Box& b, float v) {
    rtog::forEachCell(b, [&](const rtog::Key& k) {
      ++cells;
      planes.insert(k.z);
      const std::int64_t cx = std::int64_t(k.x) - g.x0, cy = std::int64_t(k.y) - g.y0;
      if (cx < 0 || cy < 0 || cx >= g.p.cols || cy >= g.p.rows || grid.getRawMap()[std::size_t(cy * g.p.cols + cx)] == 0) {
        ++misplaced;
        return;
      }
      wrong_values += !(std::fabs(rtog::probability(v) - (1.0 - grid.getCell(int(cx), int(cy)))) <= 1e-6);
    });
  });
  std::printf("prior image %d x %d pixels, %zu known to MRPT's grid, %zu cells in the prior map\n", g.p.cols, g.p.rows,
              known, cells);
  EXPECT_GT(known, 10000u);
  EXPECT_EQ(cells, known);
  EXPECT_EQ(misplaced, 0u);
  EXPECT_EQ(wrong_values, 0u);
  EXPECT_EQ(planes.size(), 1u);
}

TEST(CliImage, BadRequestsAreOneErrorLineAndNoOutput) {
  const std::string d = scratch("image_bad");
  std::string out;
  ASSERT_EQ(run("build --rawlog '" + kSena + "' --resolution 0.2 --scans 0:20 --out " + d + "/m.rtog", &out), 0) << out;
  const auto before = entries(d);
  const std::string o = " --out " + d + "/r.json --png " + d + "/r.png";
  for (const auto& [args, code] : std::vector<std::pair<std::string, int>>{
           {"image " + d + "/m.rtog --band 2 1" + o, 1},
           {"image " + d + "/m.rtog --threshold 1.5" + o, 1},
           {"image " + d + "/m.rtog --open 2" + o, 1},
           {"image " + d + "/m.rtog --blur 0" + o, 2},
           {"image " + d + "/m.rtog --slice-z 0 --band 0 1" + o, 2},
           {"image " + d + "/missing.rtog" + o, 1},
           {"image " + d + "/m.rtog --out " + d + "/m.rtog", 1},
           {"image " + d + "/m.rtog", 2}}) {
    EXPECT_EQ(run(args, &out), code) << args << "\n" << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << "\n" << out;
    EXPECT_EQ(out.rfind("rtog: error: ", 0), 0u) << out;
  }
  EXPECT_EQ(entries(d), before);
}

// A blur of 1 km on a map some 40 m wide: the known cells' mean, nearly, computed with the kernel
// clipped to the image (before: a kernel of 120,001 taps a row, minutes). The tool must finish
// within 60 s, with the library's result.
TEST(CliImage, AHugeBlurFinishesWithTheLibrarysResult) {
  const std::string d = scratch("image_huge_blur");
  std::string out;
  ASSERT_EQ(run("build --rawlog '" + kSena + "' --resolution 0.05 --out " + d + "/m.rtog", &out), 0) << out;
  ASSERT_EQ(run("image " + d + "/m.rtog --blur 1000 --threshold 0.3 --out " + d + "/r.json", &out, "timeout 60 "), 0) << out;
  const rtog::image::GridImage g =
      rtog::image::blur(rtog::image::bandImage(rtog::cli::loadMap(d + "/m.rtog"), -1000, 1000), 1000);
  std::ifstream in(d + "/r.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["occupied_cells"].get<int>(), cv::countNonZero(rtog::image::threshold(g, 0.3)));
}
