// `rtog prior` as a user runs it: Debian's Malaga campus .gridmap and a blueprint image become
// maps whose cells are the prior's, drawn towards 0.5 by --confidence (the same map the library
// call gives); bad input is one error line, a non-zero exit and no output file.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include <mrpt/img/CImage.h>

#include "cli_helpers.hpp"
#include "commands.hpp"
#include "map_cells.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace {
using rtog_cli_test::entries;
using rtog_cli_test::run;
using rtog_cli_test::scratch;

const std::string kMalaga = std::string(RTOG_MRPT_DATASETS) + "/2006-MalagaCampus.gridmap.gz";
}  // namespace

TEST(CliPrior, AGridmapIsTheLibrarysPrior) {
  const std::string d = scratch("prior_gridmap");
  std::string out;
  ASSERT_EQ(run("prior --gridmap " + kMalaga + " --confidence 0.8 --out " + d + "/m.rtog", &out), 0) << out;
  EXPECT_NE(out.find("1915925 known cells"), std::string::npos) << out;
  rtog::CRTreeOccupancyGridMap lib(0.1);
  rtog::TPriorMapOptions p;
  p.priorMap = kMalaga;
  p.priorConfidence = 0.8;
  lib.loadPrior(p);
  EXPECT_EQ(rtog::test::cellsOf(rtog::cli::loadMap(d + "/m.rtog")), rtog::test::cellsOf(lib.map()));
}

TEST(CliPrior, AnImageIsPlacedAtItsOrigin) {
  const std::string d = scratch("prior_image");
  {
    mrpt::img::CImage img(8, 4, mrpt::img::CH_GRAY);
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 8; ++x) *img(x, y) = x < 4 ? 0 : 255;  // black left half, white right half
    ASSERT_TRUE(img.saveToFile(d + "/b.png"));
  }
  std::string out;
  ASSERT_EQ(run("prior --image " + d + "/b.png --resolution 0.25 --origin -1 2 --confidence 0.9 --out " + d + "/m.rtog", &out), 0)
      << out;
  const rtog::OccupancyMap m = rtog::cli::loadMap(d + "/m.rtog");
  EXPECT_EQ(m.cellCount(), 32);
  // The image as MRPT's own grid reads it (white is P(free) 0.984 there, not 1), drawn to 0.5.
  mrpt::maps::COccupancyGridMap2D grid;
  ASSERT_TRUE(grid.loadFromBitmapFile(d + "/b.png", 0.25f, mrpt::math::TPoint2D(4, -8)));
  ASSERT_EQ(grid.getXMin(), -1.0f);
  ASSERT_EQ(grid.getYMin(), 2.0f);
  const auto expected = [&](double x, double y) { return 0.5 + 0.8 * ((1.0 - grid.getPos(x, y)) - 0.5); };
  const auto at = [&](double x, double y) { return m.logOdds(m.lattice().key(Eigen::Vector3d(x, y, 0.1))); };
  ASSERT_TRUE(at(-0.875, 2.125).has_value());
  EXPECT_NEAR(rtog::probability(*at(-0.875, 2.125)), expected(-0.875, 2.125), 1e-6);  // black, lower-left
  EXPECT_GT(rtog::probability(*at(-0.875, 2.125)), 0.89);
  EXPECT_NEAR(rtog::probability(*at(0.875, 2.875)), expected(0.875, 2.875), 1e-6);  // white, upper-right
  EXPECT_LT(rtog::probability(*at(0.875, 2.875)), 0.12);
  EXPECT_FALSE(at(-1.125, 2.125).has_value());
}

TEST(CliPrior, BadInputIsOneErrorLineAndNoOutput) {
  const std::string d = scratch("prior_bad");
  {
    mrpt::img::CImage img(4, 4, mrpt::img::CH_GRAY);
    ASSERT_TRUE(img.saveToFile(d + "/b.png"));
  }
  std::ofstream(d + "/text.gridmap") << "not a grid\n";
  const auto before = entries(d);
  for (const std::string& args : {"prior --out " + d + "/m.rtog",                                              // no input
                                 "prior --image " + d + "/b.png --gridmap " + kMalaga + " --out " + d + "/m.rtog",  // two
                                 "prior --image " + d + "/b.png --confidence 0.4 --out " + d + "/m.rtog",
                                 "prior --image " + d + "/b.png --confidence 0.5 --out " + d + "/m.rtog",
                                 "prior --image " + d + "/b.png --resolution 0 --out " + d + "/m.rtog",
                                 "prior --image " + d + "/b.png --origin nan 0 --out " + d + "/m.rtog",
                                 "prior --gridmap " + kMalaga + " --resolution 0.1 --out " + d + "/m.rtog",  // image only
                                 "prior --gridmap " + d + "/b.png --out " + d + "/m.rtog",                  // not named so
                                 "prior --gridmap " + d + "/text.gridmap --out " + d + "/m.rtog",           // not a grid
                                 "prior --image " + d + "/text.gridmap --out " + d + "/m.rtog",
                                 "prior --image " + d + "/b.png --out " + d + "/b.png",                     // the input
                                 "prior --image " + d + "/missing.png --out " + d + "/m.rtog",
                                 "prior --image " + d + "/b.png"}) {                                         // no --out
    std::string out;
    const int rc = run(args, &out);
    EXPECT_NE(rc, 0) << args;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << ": " << out;
    EXPECT_EQ(out.rfind("rtog: error: ", 0), 0u) << args << ": " << out;
  }
  EXPECT_EQ(entries(d), before);
}
