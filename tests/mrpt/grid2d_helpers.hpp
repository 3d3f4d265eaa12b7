// Shared fixtures of the 2D-view tests: a map of real SENA scans and the Malaga campus gridmap.
#pragma once

#include <gtest/gtest.h>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "derived_scan.hpp"
#include "test_helpers.hpp"

namespace rtog_test {

struct SenaFixture {
  rtog::CRTreeOccupancyGridMap map{0.05};
  mrpt::obs::CObservation2DRangeScan::Ptr scan;  // NOT inserted into the map
  mrpt::poses::CPose3D pose;                      // its odometry pose
};

// Map from every second frame of the first 40; the probe is frame 19 (odd: not inserted).
inline constexpr int kProbe = 19;
inline const SenaFixture& senaFixture() {
  static SenaFixture f = [] {
    SenaFixture fx;
    auto frames = loadOdometryFrames(dataset(kSena), 40);
    for (std::size_t i = 0; i < frames.size(); i += 2) frames[i].sf->insertObservationsInto(fx.map, frames[i].pose);
    fx.scan = frames[kProbe].sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
    fx.pose = frames[kProbe].pose;
    return fx;
  }();
  return f;
}

/// The grid the fixture's map claims to be: a stock COccupancyGridMap2D of the mrpt_grid preset's
/// initial extent (-10 to 10 m), resolution and default options that inserted the same scans itself.
inline const mrpt::maps::COccupancyGridMap2D& senaStockGrid() {
  static const mrpt::maps::COccupancyGridMap2D g = [] {
    mrpt::maps::COccupancyGridMap2D s(-10, 10, -10, 10, 0.05f);
    auto frames = loadOdometryFrames(dataset(kSena), 40);
    for (std::size_t i = 0; i < frames.size(); i += 2) frames[i].sf->insertObservationsInto(s, frames[i].pose);
    return s;
  }();
  return g;
}

/// The view and the stock grid built by insertion (senaStockGrid) hold the same grid: geometry
/// and every cell (the queries the tests compare then read the same cells).
inline void expectViewIsStockGrid(const rtog::CRTreeOccupancyGridMap& m, const mrpt::maps::COccupancyGridMap2D& stock) {
  const auto view = m.gridView();
  ASSERT_EQ(view->getXMin(), stock.getXMin());
  ASSERT_EQ(view->getYMin(), stock.getYMin());
  ASSERT_EQ(view->getSizeX(), stock.getSizeX());
  ASSERT_EQ(view->getSizeY(), stock.getSizeY());
  ASSERT_EQ(view->getResolution(), stock.getResolution());
  std::size_t differ = 0, first = 0;
  for (std::size_t i = view->getRawMap().size(); i-- > 0;)
    if (view->getRawMap()[i] != stock.getRawMap()[i]) ++differ, first = i;
  ASSERT_EQ(differ, 0u) << "cells differ from the stock grid's, the first at (" << first % stock.getSizeX() << ", "
                        << first / stock.getSizeX() << "): " << int(view->getRawMap()[first]) << " vs "
                        << int(stock.getRawMap()[first]);
}

/// Poses displaced by +-0.3 m in x and y and +-10 deg in yaw.
inline std::vector<mrpt::poses::CPose3D> displaced(const mrpt::poses::CPose3D& p) {
  std::vector<mrpt::poses::CPose3D> out;
  for (double d : {-0.3, 0.3}) {
    out.push_back(p + mrpt::poses::CPose3D(d, 0, 0, 0, 0, 0));
    out.push_back(p + mrpt::poses::CPose3D(0, d, 0, 0, 0, 0));
  }
  for (double a : {-10.0, 10.0}) out.push_back(p + mrpt::poses::CPose3D(0, 0, 0, mrpt::DEG2RAD(a), 0, 0));
  return out;
}

/// A plain COccupancyGridMap2D with the same geometry and cells (through MRPT's serialization,
/// so that none of the view's caches come along).
inline mrpt::maps::COccupancyGridMap2D stockCopy(const mrpt::maps::COccupancyGridMap2D& g) {
  mrpt::io::CMemoryStream buf;
  auto ar = mrpt::serialization::archiveFrom(buf);
  ar << g;
  buf.Seek(0);
  mrpt::maps::COccupancyGridMap2D s;
  ar >> s;
  EXPECT_TRUE(s.getRawMap() == g.getRawMap());
  return s;
}

struct MalagaFixture {
  mrpt::maps::COccupancyGridMap2D grid;  // a .gridmap(.gz) as MRPT loads it
  rtog::CRTreeOccupancyGridMap map;      // the same file through loadFromGridmapFile
};

/// One of MRPT's datasets' .gridmap(.gz) files, loaded both ways.
inline MalagaFixture gridmapFixture(const std::string& name) {
  MalagaFixture fx;
  const std::string file = dataset(name);
  mrpt::io::CFileGZInputStream in(file);
  auto ar = mrpt::serialization::archiveFrom(in);
  ar >> fx.grid;
  if (!fx.map.loadFromGridmapFile(file)) throw std::runtime_error("cannot import " + file);
  return fx;
}

inline const MalagaFixture& malagaFixture() {
  static const MalagaFixture f = gridmapFixture("2006-MalagaCampus.gridmap.gz");
  return f;
}

}  // namespace rtog_test
