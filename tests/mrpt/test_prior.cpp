// Prior maps (doc/priors.md): Debian's Malaga campus .gridmap, and a blueprint image, as a map's
// first layer through `priorMap` in _creationOpts (as MRPT's apps create maps), then SENA's
// 2D scans by the normal update. Oracles: the prior's own cells, a map of the scans alone, and
// MRPT's COccupancyGridMap2D loaded from the same file and given the same scans.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/serialization/CArchive.h>

#include "map_cells.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;
using mrpt::maps::COccupancyGridMap2D;

namespace {

const std::string kMalaga = "2006-MalagaCampus.gridmap.gz";

COccupancyGridMap2D readGrid(const std::string& file) {
  COccupancyGridMap2D g;
  mrpt::io::CFileGZInputStream f(file);
  auto ar = mrpt::serialization::archiveFrom(f);
  ar >> g;
  return g;
}

// No clamp within reach (as in test_fusion.cpp): the update is a plain sum of log-odds.
constexpr const char* kUnclamped =
    "sensorModelPreset=octomap\nmaxOccupancyUpdateCertainty=0.55\nclampingMin=1e-30\nclampingMax=0.99999994\n";

std::vector<PosedFrame> senaFrames() {
  std::vector<PosedFrame> frames;
  const auto all = loadOdometryFrames(dataset(kSena));
  for (std::size_t i = 0; i < all.size(); i += 5) frames.push_back(all[i]);
  return frames;
}

}  // namespace

// Every known cell of the .gridmap becomes one cell at P = 0.5 + (2c - 1)(p - 0.5); SENA's scans
// then add their evidence: cells they never reach keep the prior bit for bit, cells they reach
// hold the prior plus what the scans alone give (a sum without clamps), the rest are the scans'.
TEST(Prior, MalagaGridmapThenSenaScans) {
  const std::string creation = "priorMap=" + dataset(kMalaga) +
                               "\npriorConfidence=0.8\n"
                               // the prior's layer at the laser's height (0.3 m), the band the 2D view shows
                               "gridView_minZ=0.3\ngridView_maxZ=0.3\n";
  const auto m = mapFromSections(creation, kUnclamped);
  const COccupancyGridMap2D grid = readGrid(dataset(kMalaga));
  ASSERT_EQ(m->resolution(), grid.getResolution());
  const auto prior = rtog::test::cellsOf(m->map());
  {
    std::size_t known = 0;
    for (const auto c : grid.getRawMap()) known += c != 0;
    ASSERT_EQ(prior.size(), known);
    // Each cell's value from its grid cell, drawn towards 0.5.
    const rtog::Lattice& lat = m->map().lattice();
    for (std::size_t i = 0; i < prior.size(); i += 997) {
      const rtog::Key k = rtog::unpackKey(prior[i].first);
      const Eigen::Vector3d c = lat.cellCenter(k);
      const int cx = grid.x2idx(c.x()), cy = grid.y2idx(c.y());
      const double p = 1.0 - grid.getCell(cx, cy);  // P(occupied)
      EXPECT_NEAR(rtog::probability(prior[i].second), 0.5 + 0.6 * (p - 0.5), 1e-4);
      EXPECT_NEAR(c.z(), 0.3, 0.5 * grid.getResolution());
    }
  }
  const auto frames = senaFrames();
  // On the prior's lattice exactly: MRPT's float 0.08 (0.0799999982 as a double), not 0.08.
  rtog::CRTreeOccupancyGridMap alone(m->resolution(), mapFromSections("", kUnclamped)->insertionOptions);
  for (const auto& f : frames)
    for (const auto& obs : *f.sf) m->insertObservation(*obs, f.pose), alone.insertObservation(*obs, f.pose);
  EXPECT_EQ(m->map().checkInvariants(), "");
  const auto after = rtog::test::cellsOf(m->map()), scans = rtog::test::cellsOf(alone.map());
  std::map<std::uint64_t, float> priorOf(prior.begin(), prior.end()), scanOf(scans.begin(), scans.end());
  std::size_t untouched = 0, both = 0, scanOnly = 0;
  double worst = 0;
  for (const auto& [key, v] : after) {
    const auto p = priorOf.find(key);
    const auto s = scanOf.find(key);
    ASSERT_TRUE(p != priorOf.end() || s != scanOf.end());
    if (s == scanOf.end()) {
      ++untouched;
      ASSERT_EQ(v, p->second);  // bit for bit
    } else if (p == priorOf.end()) {
      ++scanOnly;
      worst = std::max(worst, double(std::fabs(v - s->second)));
    } else {
      ++both;
      worst = std::max(worst, double(std::fabs(v - (p->second + s->second))));
    }
  }
  EXPECT_EQ(after.size(), untouched + both + scanOnly);
  EXPECT_EQ(untouched + both, prior.size());
  std::printf("Malaga prior (%zu cells) + %zu SENA frames: %zu cells untouched, %zu updated, %zu new; "
              "largest difference from prior + scans %.3g\n",
              prior.size(), frames.size(), untouched, both, scanOnly, worst);
  EXPECT_GT(both, 10000u);  // the scans do reach the prior
  EXPECT_GT(untouched, 1000000u);
  EXPECT_LT(worst, 1e-5);
}

// With full confidence, in the mrpt_grid preset, the prior and SENA's scans give the stock grid
// loaded from the same file and given the same scans, cell for cell (the drop-in claim).
TEST(Prior, FullConfidenceIsTheStockGridLoadedFromTheFile) {
  const auto m = mapFromSections("priorMap=" + dataset(kMalaga) + "\npriorConfidence=1\n", "");
  COccupancyGridMap2D stock = readGrid(dataset(kMalaga));
  // The file holds the options it was built with (maxDistanceInsertion 25 m, ...); the prior
  // map inserts by the .ini's, here the defaults, and so must the stock grid.
  stock.insertionOptions = COccupancyGridMap2D::TInsertionOptions();
  const auto frames = senaFrames();
  for (const auto& f : frames)
    for (const auto& obs : *f.sf) m->insertObservation(*obs, f.pose), stock.insertObservation(*obs, f.pose);
  const auto view = m->gridView();
  ASSERT_EQ(view->getSizeX(), stock.getSizeX());
  ASSERT_EQ(view->getSizeY(), stock.getSizeY());
  EXPECT_EQ(view->getXMin(), stock.getXMin());
  EXPECT_EQ(view->getYMin(), stock.getYMin());
  std::size_t differ = 0;
  // The file holds a few cells at -128, which MRPT reads as -127, its bound (CLogOddsGridMapLUT::l2p):
  // compared as MRPT reads them.
  const auto read = [](std::int8_t c) { return std::max<int>(c, -127); };
  for (std::size_t i = 0; i < stock.getRawMap().size(); ++i)
    differ += read(view->getRawMap()[i]) != read(stock.getRawMap()[i]);
  EXPECT_EQ(differ, 0u);
}

// MRPT's apps clear a map before they fill it (observations2map: loadFromSimpleMap; the SLAM
// apps at start): clear() returns to the prior, in copies too; a loaded grid clears to empty.
TEST(Prior, ClearReturnsToThePrior) {
  const auto m = mapFromSections("priorMap=" + dataset(kMalaga) + "\npriorConfidence=0.9\n", "");
  const auto prior = rtog::test::cellsOf(m->map());
  const auto frame = m->gridFrame();
  const auto frames = senaFrames();
  for (std::size_t i = 0; i < 5; ++i)
    for (const auto& obs : *frames[i].sf) m->insertObservation(*obs, frames[i].pose);
  ASSERT_NE(rtog::test::cellsOf(m->map()), prior);
  rtog::CRTreeOccupancyGridMap copy(*m);
  m->clear();
  EXPECT_EQ(rtog::test::cellsOf(m->map()), prior);
  EXPECT_EQ(m->gridFrame().x_min, frame.x_min);
  EXPECT_EQ(m->gridFrame().size_y, frame.size_y);
  copy.clear();
  EXPECT_EQ(rtog::test::cellsOf(copy.map()), prior);
  copy.loadFromGrid(readGrid(dataset(kMalaga)));
  copy.clear();
  EXPECT_EQ(copy.map().leafCount(), 0u);
}

// Yesterday's map as today's prior, on data whose frames agree by construction: the stock grid
// of SENA's first half, saved as a PNG (MRPT's saveAsBitmapFile), is the prior of a map that then
// sees only the second half. Against the stock grid of the whole loop, the map with the prior
// classifies more cells as that grid does than the second half alone. With RTOG_PRIOR_PICTURES=DIR
// the maps are left in DIR as .rtog files (doc/priors.md draws them with `rtog export`).
TEST(Prior, YesterdaysMapAsTodaysPrior) {
  const auto all = loadOdometryFrames(dataset(kSena));
  const std::size_t half = all.size() / 2;
  COccupancyGridMap2D yesterday(-10, 10, -10, 10, 0.05f), whole(-10, 10, -10, 10, 0.05f);
  for (std::size_t i = 0; i < all.size(); ++i)
    for (const auto& obs : *all[i].sf) {
      if (i < half) yesterday.insertObservation(*obs, all[i].pose);
      whole.insertObservation(*obs, all[i].pose);
    }
  const char* keep = std::getenv("RTOG_PRIOR_PICTURES");
  const auto dir = keep ? std::filesystem::path(keep) : std::filesystem::temp_directory_path() / ("rtog_prior_y_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string png = (dir / "sena_first_half.png").string();
  ASSERT_TRUE(yesterday.saveAsBitmapFile(png));
  char origin[160];
  std::snprintf(origin, sizeof origin, "\npriorResolution=0.05\npriorOriginX=%.9g\npriorOriginY=%.9g\n", yesterday.getXMin(),
                yesterday.getYMin());
  const auto today = mapFromSections("priorMap=" + png + origin + "priorConfidence=0.7\n", "");
  const auto alone = mapFromSections("resolution=0.05\n", "");
  // The image holds the first half where the stock grid had it (P(free) as 8-bit grey).
  {
    std::size_t known = 0, same = 0;
    const auto view = today->gridView();
    for (unsigned cy = 0; cy < yesterday.getSizeY(); ++cy)
      for (unsigned cx = 0; cx < yesterday.getSizeX(); ++cx) {
        const float p = yesterday.getCell(cx, cy);
        if (std::fabs(p - 0.5f) < 0.05f) continue;
        ++known;
        same += (view->getPos(yesterday.idx2x(cx), yesterday.idx2y(cy)) < 0.5f) == (p < 0.5f);
      }
    EXPECT_GT(double(same), 0.995 * double(known)) << same << " of " << known;
  }
  for (std::size_t i = half; i < all.size(); ++i)
    for (const auto& obs : *all[i].sf) today->insertObservation(*obs, all[i].pose), alone->insertObservation(*obs, all[i].pose);
  const auto agreement = [&](const rtog::CRTreeOccupancyGridMap& m) {
    const auto view = m.gridView();
    std::size_t known = 0, same = 0;
    for (unsigned cy = 0; cy < whole.getSizeY(); ++cy)
      for (unsigned cx = 0; cx < whole.getSizeX(); ++cx) {
        const float p = whole.getCell(cx, cy);
        if (p == 0.5f) continue;
        ++known;
        const float q = view->getPos(whole.idx2x(cx), whole.idx2y(cy));
        same += q != 0.5f && (q < 0.5f) == (p < 0.5f);
      }
    return double(same) / double(known);
  };
  const double with_prior = agreement(*today), without = agreement(*alone);
  std::printf("SENA: the whole loop's stock grid classified alike by the second half alone %.4f, by it on the "
              "first half's PNG as prior %.4f\n", without, with_prior);
  EXPECT_GT(with_prior, without + 0.1);
  if (keep) {
    std::ofstream a(dir / "sena_prior_and_second_half.rtog", std::ios::binary), b(dir / "sena_second_half.rtog", std::ios::binary);
    today->map().write(a);
    alone->map().write(b);
  } else {
    std::filesystem::remove_all(dir);
  }
}

// A blueprint image: its lower-left corner at priorOrigin, a pixel of priorResolution, black
// occupied, white free, mid-grey unknown.
TEST(Prior, ABlueprintImageIsPlacedAndTrustedAsStated) {
  const auto dir = std::filesystem::temp_directory_path() / ("rtog_prior_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string png = (dir / "blueprint.png").string();
  {
    mrpt::img::CImage img(20, 10, mrpt::img::CH_GRAY);
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 20; ++x) *img(x, y) = x < 5 ? 0 : (x < 10 ? 255 : 128);  // black, white, grey columns
    ASSERT_TRUE(img.saveToFile(png));
  }
  const auto m = mapFromSections("priorMap=" + png +
                             "\npriorResolution=0.1\npriorOriginX=2\npriorOriginY=-3\npriorConfidence=0.75\n",
                         "sensorModelPreset=octomap\n");
  EXPECT_EQ(m->resolution(), 0.1f);
  const rtog::OccupancyMap& map = m->map();
  EXPECT_EQ(map.cellCount(), 10 * 10);  // the grey half is unknown
  const auto at = [&](double x, double y) { return map.logOdds(map.lattice().key(Eigen::Vector3d(x, y, 0.05))); };
  ASSERT_TRUE(at(2.05, -2.95).has_value());                               // the lower-left pixel
  EXPECT_NEAR(rtog::probability(*at(2.05, -2.95)), 0.75, 0.01);           // black: c
  EXPECT_NEAR(rtog::probability(*at(2.75, -2.05)), 0.25, 0.01);           // white: 1 - c
  EXPECT_FALSE(at(3.55, -2.5).has_value());                               // grey: unknown
  EXPECT_FALSE(at(1.95, -2.95).has_value());                              // left of the image
  EXPECT_FALSE(at(2.05, -1.95).has_value());                              // above it
  std::filesystem::remove_all(dir);
}

// Bad values are refused by key when the .ini is read; unreadable files when the map is made.
TEST(Prior, BadPriorsAreRefusedClearly) {
  const auto message = [](const std::string& creation) -> std::string {
    try {
      (void)mapFromSections(creation, "");
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message("priorMap=x.png\npriorConfidence=0.5").find("priorConfidence"), std::string::npos);
  EXPECT_NE(message("priorMap=x.png\npriorConfidence=nan").find("priorConfidence"), std::string::npos);
  EXPECT_NE(message("priorMap=x.png\npriorResolution=0").find("priorResolution"), std::string::npos);
  EXPECT_NE(message("priorMap=x.png\npriorOriginX=inf").find("priorOriginX"), std::string::npos);
  EXPECT_NE(message("priorMap=/nonexistent/blueprint.png").find("cannot open"), std::string::npos);
  // A file that is neither: this source file, as an image and as a gridmap.
  EXPECT_NE(message("priorMap=" + std::string(__FILE__)).find("not an image"), std::string::npos);
  const auto dir = std::filesystem::temp_directory_path() / ("rtog_prior_bad_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto fake = dir / "fake.gridmap";
  std::filesystem::copy_file(__FILE__, fake);
  EXPECT_NE(message("priorMap=" + fake.string()).find("not a serialized COccupancyGridMap2D"), std::string::npos);
  std::filesystem::remove_all(dir);
  // The API refuses a confidence outside (0.5, 1] and leaves the map as it was.
  rtog::CRTreeOccupancyGridMap m(0.1);
  EXPECT_THROW(m.loadPrior(COccupancyGridMap2D(), 1.5), std::invalid_argument);
  EXPECT_EQ(m.map().leafCount(), 0u);
}
