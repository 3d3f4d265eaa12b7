// The mrpt_grid preset against MRPT's own COccupancyGridMap2D, shared by the fidelity tests: stock
// configs with the grid section renamed, the frames of MRPT's datasets, and the cell-by-cell
// comparison of a map with the stock grid.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimpleMap.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

namespace rtog_test {

inline const std::string kConfigs = "/usr/share/mrpt/config_files/";

inline std::string readText(const std::string& file) {
  std::ifstream f(file);
  if (!f) throw std::runtime_error("cannot read " + file);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

inline std::string replaceAll(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = 0; (p = s.find(from, p)) != std::string::npos; p += to.size()) s.replace(p, from.size(), to);
  return s;
}

/// The stock config's grid sections, the map renamed to `type` as a user would paste them, with
/// `extra` lines added to the map's _insertOpts.
inline mrpt::maps::CMultiMetricMap mapsFrom(const std::string& ini, const std::string& prefix, const std::string& type,
                                            const std::string& extra = "") {
  std::string text = type == "occupancyGrid"
                         ? ini
                         : replaceAll(replaceAll(ini, "occupancyGrid_count", type + "_count"),
                                      "_occupancyGrid_00_", "_" + type + "_00_");
  if (!extra.empty()) {
    const std::string sec = "[" + prefix + "_" + type + "_00_insertOpts]";
    const std::size_t at = text.find(sec);
    if (at == std::string::npos) throw std::runtime_error("no section " + sec);
    text.insert(at + sec.size(), "\n" + extra + "\n");
  }
  mrpt::config::CConfigFileMemory cfg(text);
  mrpt::maps::TSetOfMetricMapInitializers inits;
  inits.loadFromConfigFile(cfg, prefix);
  mrpt::maps::CMultiMetricMap mm;
  mm.setListOfMaps(inits);
  return mm;
}

struct Figures {
  std::size_t cells = 0, differ = 0, max_step = 0;
};

inline Figures compareCells(const mrpt::maps::COccupancyGridMap2D& a, const mrpt::maps::COccupancyGridMap2D& b) {
  Figures f;
  EXPECT_EQ(a.getXMin(), b.getXMin());
  EXPECT_EQ(a.getXMax(), b.getXMax());
  EXPECT_EQ(a.getYMin(), b.getYMin());
  EXPECT_EQ(a.getYMax(), b.getYMax());
  EXPECT_EQ(a.getSizeX(), b.getSizeX());
  EXPECT_EQ(a.getSizeY(), b.getSizeY());
  if (a.getSizeX() != b.getSizeX() || a.getSizeY() != b.getSizeY()) return f;
  for (unsigned y = 0; y < a.getSizeY(); ++y) {
    const auto* ra = a.getRow(static_cast<int>(y));
    const auto* rb = b.getRow(static_cast<int>(y));
    for (unsigned x = 0; x < a.getSizeX(); ++x, ++f.cells) {
      if (ra[x] == rb[x]) continue;
      ++f.differ;
      f.max_step = std::max<std::size_t>(f.max_step, static_cast<std::size_t>(std::abs(int(ra[x]) - int(rb[x]))));
    }
  }
  return f;
}

/// The R-tree map's cells of the grid's plane against the grid: a cell the map never observed
/// must be 0 in the grid, an observed one must hold the grid's value as -cell / 16.
inline Figures compareRTree(const mrpt::maps::COccupancyGridMap2D& g, const rtog::CRTreeOccupancyGridMap& m) {
  Figures f;
  const rtog::TGridFrame2D& fr = m.gridFrame();
  EXPECT_EQ(fr.x_min, g.getXMin());
  EXPECT_EQ(fr.y_min, g.getYMin());
  EXPECT_EQ(fr.size_x, g.getSizeX());
  EXPECT_EQ(fr.size_y, g.getSizeY());
  const auto ox = static_cast<std::int32_t>(std::lround(double(fr.x_min) / fr.resolution));
  const auto oy = static_cast<std::int32_t>(std::lround(double(fr.y_min) / fr.resolution));
  const std::size_t sx = g.getSizeX(), sy = g.getSizeY();
  std::vector<int> ours(sx * sy, 0);
  std::vector<char> known(sx * sy, 0);
  std::size_t outside = 0;
  m.map().forEachLeaf([&](const rtog::Box& b, float v) {
    rtog::forEachCell(b, [&](const rtog::Key& k) {
      const std::int64_t x = k.x - ox, y = k.y - oy;
      if (k.z != fr.layer || x < 0 || y < 0 || x >= std::int64_t(sx) || y >= std::int64_t(sy)) {
        ++outside;
        return;
      }
      const float c = -v * 16.0f;
      EXPECT_EQ(c, std::round(c)) << "value " << v << " is no int8 cell";
      ours[std::size_t(y) * sx + std::size_t(x)] = static_cast<int>(std::lround(c));
      known[std::size_t(y) * sx + std::size_t(x)] = 1;
    });
  });
  EXPECT_EQ(outside, 0u);
  for (std::size_t y = 0; y < sy; ++y) {
    const auto* row = g.getRow(static_cast<int>(y));
    for (std::size_t x = 0; x < sx; ++x, ++f.cells) {
      const int want = row[x], have = ours[y * sx + x];
      if (want == have) continue;
      ++f.differ;
      f.max_step = std::max<std::size_t>(f.max_step, static_cast<std::size_t>(std::abs(want - have)));
    }
  }
  return f;
}

struct Frame {
  mrpt::poses::CPose3D pose;
  mrpt::obs::CSensoryFrame::Ptr sf;
};

inline std::vector<Frame> simplemapFrames(const std::string& file) {
  mrpt::maps::CSimpleMap sm;
  if (!sm.loadFromFile(file)) throw std::runtime_error("cannot load " + file);
  std::vector<Frame> out;
  for (const auto& kf : sm) out.push_back({kf.pose->getMeanVal(), kf.sf});
  return out;
}

inline std::vector<Frame> rawlogFrames(const std::string& file) {
  std::vector<Frame> out;
  for (auto& f : loadOdometryFrames(file)) out.push_back({f.pose, f.sf});
  return out;
}

}  // namespace rtog_test
