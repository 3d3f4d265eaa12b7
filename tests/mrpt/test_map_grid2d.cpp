// The 2D view of CRTreeOccupancyGridMap and the COccupancyGridMap2D API on it, each cross-checked
// against a stock COccupancyGridMap2D that inserted the same real SENA scans (or read the same
// gridmap file). Its likelihoods: test_map_grid2d_likelihood.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <mrpt/img/CImage.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include "grid2d_helpers.hpp"

using namespace rtog_test;
using mrpt::poses::CPose3D;

TEST(MapGrid2D, ViewCellsAreTheBandsHighestLogOdds) {
  const SenaFixture& f = senaFixture();
  const auto view = f.map.gridView();
  const auto& m = f.map.map();
  const rtog::Box kb = m.keyBounds();
  ASSERT_FALSE(kb.isEmpty());
  // mrpt_grid: the view is the grid the scans were stepped in (its geometry, margins included).
  const rtog::TGridFrame2D& fr = f.map.gridFrame();
  EXPECT_EQ(view->getXMin(), fr.x_min);
  EXPECT_EQ(view->getYMax(), fr.y_max);
  EXPECT_EQ(view->getSizeX(), fr.size_x);
  EXPECT_EQ(view->getSizeY(), fr.size_y);
  const auto gx0 = std::lround(double(view->getXMin()) / view->getResolution());
  const auto gy0 = std::lround(double(view->getYMin()) / view->getResolution());
  std::size_t known = 0;
  for (int y = kb.min.y; y <= kb.max.y; y += 3)
    for (int x = kb.min.x; x <= kb.max.x; x += 3) {
      float best = -1e9f;
      bool any = false;
      for (int z = kb.min.z; z <= kb.max.z; ++z)
        if (const auto v = m.logOdds(rtog::Key{x, y, z})) best = std::max(best, *v), any = true;
      // Values that are int8 cells (-l / 16, the mrpt_grid preset's) exactly; others through p2l.
      const float l = -16.0f * best;
      const int8_t want = !any ? 0
                          : l == std::round(l) && std::abs(l) <= 127
                              ? static_cast<int8_t>(l)
                              : mrpt::maps::COccupancyGridMap2D::p2l(float(1.0 - rtog::probability(best)));
      const auto got = view->getRawMap()[(y - gy0) * view->getSizeX() + (x - gx0)];
      ASSERT_EQ(int(got), int(want)) << "cell " << x << "," << y;
      known += any;
    }
  EXPECT_GT(known, 1000u);
}

TEST(MapGrid2D, BandAndCacheInvalidation) {
  const SenaFixture& f = senaFixture();
  rtog::CRTreeOccupancyGridMap m = f.map;
  const auto v1 = m.gridView();
  EXPECT_EQ(m.gridView().get(), v1.get());  // cached
  EXPECT_GT(m.gridViewCellCounts().occupied, 100u);
  m.gridViewOptions.gridView_minZ = 50;  // above every cell: all unknown
  m.gridViewOptions.gridView_maxZ = 60;
  const auto c = m.gridViewCellCounts();
  EXPECT_EQ(c.occupied + c.free, 0u);
  m.gridViewOptions = {};
  const auto before = m.gridViewCellCounts();
  auto frames = loadOdometryFrames(dataset(kSena), 60);
  // notifyMapChanged drops the view: the new one is the stock grid that inserted the scan too.
  const auto scan = frames[50].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
  ASSERT_TRUE(m.insertObservation(*scan, frames[50].pose));
  mrpt::maps::COccupancyGridMap2D stock = senaStockGrid();
  ASSERT_TRUE(stock.insertObservation(*scan, frames[50].pose));
  EXPECT_NE(m.gridView().get(), v1.get());
  expectViewIsStockGrid(m, stock);
  EXPECT_FALSE(stock.getRawMap() == senaStockGrid().getRawMap());
  const auto after = m.gridViewCellCounts();
  EXPECT_NE(after.free + after.occupied, before.free + before.occupied);
}

TEST(MapGrid2D, ImportedGridmapViewIsBitExact) {
  const MalagaFixture& g = malagaFixture();
  const auto view = g.map.gridView();
  // The view spans the known cells; the file's grid has an unknown border around them.
  const float res = g.grid.getResolution();
  const int ox = int(std::lround((view->getXMin() - g.grid.getXMin()) / res));
  const int oy = int(std::lround((view->getYMin() - g.grid.getYMin()) / res));
  ASSERT_GE(ox, 0);
  ASSERT_GE(oy, 0);
  ASSERT_LE(ox + view->getSizeX(), g.grid.getSizeX());
  ASSERT_LE(oy + view->getSizeY(), g.grid.getSizeY());
  std::size_t known = 0, mismatches = 0;
  for (unsigned y = 0; y < g.grid.getSizeY(); ++y)
    for (unsigned x = 0; x < g.grid.getSizeX(); ++x) {
      const int vx = int(x) - ox, vy = int(y) - oy;
      const bool inside = vx >= 0 && vy >= 0 && vx < int(view->getSizeX()) && vy < int(view->getSizeY());
      // -128, which the file holds in places, is -127 to MRPT (l2p reads both as its lowest value)
      // and to the mrpt_grid preset, whose cells saturate there.
      const auto want = static_cast<int8_t>(std::max<int>(g.grid.getRawMap()[y * g.grid.getSizeX() + x], -127));
      const auto got = inside ? view->getRawMap()[vy * view->getSizeX() + vx] : int8_t(0);
      mismatches += got != want;
      known += want != 0;
    }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_GT(known, 100000u);
  EXPECT_LT(g.map.map().leafCount(), g.grid.getRawMap().size() / 2);  // runs merged
}

TEST(MapGrid2D, GridApiEqualsStockGrid) {
  const SenaFixture& f = senaFixture();
  const rtog::CRTreeOccupancyGridMap& m = f.map;
  // The stock grid that inserted the same scans itself, not a copy of the view.
  const mrpt::maps::COccupancyGridMap2D& stock = senaStockGrid();
  expectViewIsStockGrid(m, stock);
  mrpt::maps::COccupancyGridMap2D::TEntropyInfo a, b;
  m.computeEntropy(a);
  stock.computeEntropy(b);
  EXPECT_DOUBLE_EQ(a.H, b.H);
  EXPECT_EQ(a.effectiveMappedCells, b.effectiveMappedCells);
  EXPECT_GT(a.effectiveMappedCells, 10000u);
  EXPECT_DOUBLE_EQ(m.getArea(), stock.getArea());
  const mrpt::poses::CPose2D p2(f.pose);
  mrpt::obs::CObservation2DRangeScan s1 = *f.scan, s2 = *f.scan;
  m.laserScanSimulator(s1, p2, 0.5f, 361);
  stock.laserScanSimulator(s2, p2, 0.5f, 361);
  ASSERT_EQ(s1.getScanSize(), s2.getScanSize());
  std::size_t valid = 0;
  for (std::size_t i = 0; i < s1.getScanSize(); ++i) {
    EXPECT_EQ(s1.getScanRange(i), s2.getScanRange(i));
    valid += s1.getScanRangeValidity(i);
  }
  EXPECT_GT(valid, 100u);
  // Native 3D ray casting agrees with the 2D simulation to about a cell along most beams.
  const CPose3D sensor = f.pose + f.scan->sensorPose;
  std::size_t close = 0, n = 0;
  for (double ang = -1.5; ang <= 1.5; ang += 0.05) {
    float r2 = 0;
    bool ok = false;
    stock.simulateScanRay(sensor.x(), sensor.y(), sensor.yaw() + ang, r2, ok, 20.0, 0.5f);
    float r1 = 0;
    bool ok1 = false;
    m.simulateScanRay(sensor.x(), sensor.y(), sensor.yaw() + ang, r1, ok1, 20.0, 0.5f);
    EXPECT_EQ(r1, r2);
    const auto hit = m.castRay({sensor.x(), sensor.y(), sensor.z()},
                               {std::cos(sensor.yaw() + ang), std::sin(sensor.yaw() + ang), 0.0}, 20.0);
    if (!ok || !hit) continue;
    ++n;
    close += std::abs(*hit - r2) < 0.15;
  }
  EXPECT_GT(n, 20u);
  EXPECT_GE(close, n * 8 / 10);
  // Clearance (the view) and the native nearest obstacle, at the robot's position.
  const float c1 = m.computeClearance(float(sensor.x()), float(sensor.y()), 3.0f);
  EXPECT_EQ(c1, stock.computeClearance(float(sensor.x()), float(sensor.y()), 3.0f));
  const auto d = m.nearestObstacleDistance({sensor.x(), sensor.y(), sensor.z()}, 3.0);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(*d, c1, 2 * m.resolution());
  // Cell counts, image and bitmap round trip.
  const auto c = m.gridViewCellCounts();
  std::size_t fr = 0, oc = 0;
  for (auto l : stock.getRawMap()) fr += l > 0, oc += l < 0;
  EXPECT_EQ(c.free, fr);
  EXPECT_EQ(c.occupied, oc);
  mrpt::img::CImage i1, i2;
  m.getAsImage(i1);
  stock.getAsImage(i2);
  ASSERT_EQ(i1.getWidth(), i2.getWidth());
  ASSERT_EQ(i1.getHeight(), i2.getHeight());
  std::size_t pixels_differ = 0;
  for (int y = 0; y < int(i1.getHeight()); ++y)
    for (int x = 0; x < int(i1.getWidth()); ++x) pixels_differ += *i1(x, y) != *i2(x, y);
  EXPECT_EQ(pixels_differ, 0u);
  // The bitmaps of the two, and the map loaded from the view's against the stock grid loaded
  // from the stock grid's: cell for cell.
  const std::string png = "/tmp/rtog_test_grid2d_view.png", stockFile = "/tmp/rtog_test_grid2d_stock.png";
  ASSERT_TRUE(m.saveAsBitmapFile(png));
  ASSERT_TRUE(stock.saveAsBitmapFile(stockFile));
  rtog::CRTreeOccupancyGridMap fromPng(0.1);
  ASSERT_TRUE(fromPng.loadFromBitmapFile(png, stock.getResolution()));
  mrpt::maps::COccupancyGridMap2D stockPng;
  ASSERT_TRUE(stockPng.loadFromBitmapFile(stockFile, stock.getResolution()));
  std::remove(png.c_str());
  std::remove(stockFile.c_str());
  const auto pv = fromPng.gridView();
  // The view spans the known cells; the bitmap's grid has an unknown border around them.
  const int ox = int(std::lround((pv->getXMin() - stockPng.getXMin()) / stockPng.getResolution()));
  const int oy = int(std::lround((pv->getYMin() - stockPng.getYMin()) / stockPng.getResolution()));
  std::size_t png_differ = 0, png_known = 0;
  for (int y = 0; y < int(stockPng.getSizeY()); ++y)
    for (int x = 0; x < int(stockPng.getSizeX()); ++x) {
      const int vx = x - ox, vy = y - oy;
      const bool inside = vx >= 0 && vy >= 0 && vx < int(pv->getSizeX()) && vy < int(pv->getSizeY());
      const int want = stockPng.getRawMap()[std::size_t(y) * stockPng.getSizeX() + x];
      png_differ += (inside ? int(pv->getRawMap()[std::size_t(vy) * pv->getSizeX() + vx]) : 0) != want;
      png_known += want != 0;
    }
  EXPECT_EQ(png_differ, 0u);
  EXPECT_GT(png_known, 10000u);
}

TEST(MapGrid2D, MalagaGridmapQueriesEqualStock) {
  // Against a stock grid of the view's extent: MRPT's computeEntropy counts unknown cells as
  // mapped (its table zeroes the entropy of cell value 0), so the file's wider grid differs.
  const MalagaFixture& g = malagaFixture();
  const mrpt::maps::COccupancyGridMap2D stock = stockCopy(*g.map.gridView());
  mrpt::maps::COccupancyGridMap2D::TEntropyInfo a, b;
  g.map.computeEntropy(a);
  stock.computeEntropy(b);
  EXPECT_EQ(a.effectiveMappedCells, b.effectiveMappedCells);
  EXPECT_NEAR(a.H, b.H, 1e-6 * std::abs(b.H));
  // Rays and clearance against the file's grid as MRPT loaded it (not a copy of the view).
  std::size_t rays = 0, hits = 0;
  for (float x = 0; x < 100; x += 9.7f)
    for (float y = -100; y < 80; y += 11.3f) {
      float r1, r2;
      bool v1, v2;
      g.map.simulateScanRay(x, y, 0.3, r1, v1, 30.0, 0.5f);
      g.grid.simulateScanRay(x, y, 0.3, r2, v2, 30.0, 0.5f);
      EXPECT_EQ(r1, r2) << x << ", " << y;
      EXPECT_EQ(v1, v2) << x << ", " << y;
      ++rays, hits += v2;
      EXPECT_EQ(g.map.computeClearance(x, y, 2.0f), g.grid.computeClearance(x, y, 2.0f)) << x << ", " << y;
    }
  EXPECT_GT(hits, rays / 4);
}
