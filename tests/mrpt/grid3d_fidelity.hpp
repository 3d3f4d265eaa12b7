// The mrpt_grid preset's 3D sections against MRPT's own COccupancyGridMap3D, shared by the 3D
// fidelity tests: both maps from one section text, the voxel-by-voxel comparison, a rawlog's
// observations.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/obs/CRawlog.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "test_helpers.hpp"

namespace rtog_test {

struct Pair {
  std::shared_ptr<mrpt::maps::COccupancyGridMap3D> stock;
  rtog::CRTreeOccupancyGridMap::Ptr ours;
};

/// Both maps from the same section text: ours through MRPT's map loader (as the apps make it),
/// the stock grid from its own TMapDefinition, as its map factory makes it.
inline Pair makePair(const std::string& creation, const std::string& insert, const std::string& likelihood = "") {
  const std::string body = "_creationOpts]\n" + creation + "\n[%_insertOpts]\n" + insert + "\n[%_likelihoodOpts]\n" +
                           likelihood + "\n";
  const auto section = [&](const std::string& name) {
    std::string s = "[" + name + body;
    for (std::size_t p; (p = s.find('%')) != std::string::npos;) s.replace(p, 1, name);
    return s;
  };
  const std::string ini = "[MappingApplication]\nrtreeOccupancyGrid_count=1\n" +
                          section("MappingApplication_rtreeOccupancyGrid_00") + section("G");
  Pair p;
  p.ours = std::dynamic_pointer_cast<rtog::CRTreeOccupancyGridMap>(multiMapFromIni(ini).maps.at(0));
  mrpt::config::CConfigFileMemory cfg(ini);
  mrpt::maps::COccupancyGridMap3D::TMapDefinition d;
  d.loadFromConfigFile(cfg, "G");
  p.stock = std::make_shared<mrpt::maps::COccupancyGridMap3D>(mrpt::math::TPoint3D(d.min_x, d.min_y, d.min_z),
                                                  mrpt::math::TPoint3D(d.max_x, d.max_y, d.max_z), d.resolution);
  p.stock->insertionOptions = d.insertionOpts;
  p.stock->likelihoodOptions = d.likelihoodOpts;
  return p;
}

/// Voxels that differ (printed), comparing every cell of the stock grid, and no cell of ours
/// outside it.
inline std::size_t differingCells(const Pair& p, const std::string& what) {
  const auto& g = p.stock->m_grid;
  const rtog::TGridFrame3D& f = p.ours->gridFrame3D();
  EXPECT_TRUE(f.defined);
  EXPECT_EQ(f.size_x, g.getSizeX());
  EXPECT_EQ(f.size_y, g.getSizeY());
  EXPECT_EQ(f.size_z, g.getSizeZ());
  EXPECT_EQ(f.x_min, g.getXMin());
  EXPECT_EQ(f.z_min, g.getZMin());
  if (f.size_x != g.getSizeX() || f.size_y != g.getSizeY() || f.size_z != g.getSizeZ()) return ~std::size_t{0};
  std::vector<std::int8_t> mine(g.getSizeX() * g.getSizeY() * g.getSizeZ(), 0);
  const rtog::Key o{static_cast<std::int32_t>(std::lround(f.x_min / f.resolution)),
                    static_cast<std::int32_t>(std::lround(f.y_min / f.resolution)),
                    static_cast<std::int32_t>(std::lround(f.z_min / f.resolution))};
  std::size_t outside = 0, known = 0;
  p.ours->map().forEachLeaf([&](const rtog::Box& b, float v) {
    for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
      for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
        for (std::int32_t x = b.min.x; x <= b.max.x; ++x) {
          const long cx = x - o.x, cy = y - o.y, cz = z - o.z;
          if (cx < 0 || cy < 0 || cz < 0 || cx >= long(f.size_x) || cy >= long(f.size_y) || cz >= long(f.size_z)) {
            ++outside;
            continue;
          }
          mine[(cz * f.size_y + cy) * f.size_x + cx] = static_cast<std::int8_t>(std::lround(-v * 16.0f));
        }
  });
  std::size_t differ = 0;
  for (unsigned cz = 0; cz < f.size_z; ++cz)
    for (unsigned cy = 0; cy < f.size_y; ++cy)
      for (unsigned cx = 0; cx < f.size_x; ++cx) {
        const std::int8_t s = *g.cellByIndex(cx, cy, cz);
        known += s != 0;
        differ += s != mine[(std::size_t{cz} * f.size_y + cy) * f.size_x + cx];
      }
  std::cout << what << ": " << f.size_x * std::size_t{f.size_y} * f.size_z << " cells, " << known
            << " not 0.5 in the stock grid, " << differ << " differ, " << outside << " of ours outside\n";
  EXPECT_EQ(outside, 0u);
  EXPECT_GT(known, 1000u) << "a comparison of empty grids proves nothing";
  return differ;
}

inline std::vector<mrpt::obs::CObservation::Ptr> observationsOf(const std::string& file) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(file)) throw std::runtime_error("cannot load " + file);
  std::vector<mrpt::obs::CObservation::Ptr> out;
  for (std::size_t i = 0; i < rl.size(); ++i)
    if (rl.getType(i) == mrpt::obs::CRawlog::etObservation) out.push_back(rl.getAsObservation(i));
  return out;
}

}  // namespace rtog_test
