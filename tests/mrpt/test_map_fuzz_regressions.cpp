// Inputs the fuzz targets (fuzz/, doc/reliability_fuzz.md) found to misbehave, one case each.
// Some misbehaved only as undefined behaviour: those cases fail before their fix in the
// sanitizer builds (.ci/asan, .ci/fuzz), which report it, and pass silently elsewhere.
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

using rtog::CRTreeOccupancyGridMap;

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
}

// rtog_fuzz_insert: a NaN probability reached MRPT's int8 quantization (a float to integer
// cast: undefined) in the constructor, before the options were validated.
TEST(FuzzRegressions, NaNProbabilityIsRefusedBeforeItIsQuantized) {
  for (const char* preset : {"mrpt_grid", "octomap"}) {
    CRTreeOccupancyGridMap::TInsertionOptions io;
    io.sensorModelPreset = preset;
    io.maxOccupancyUpdateCertainty = kNaN;
    EXPECT_THROW(CRTreeOccupancyGridMap(0.1, io), std::invalid_argument) << preset;
    io.maxOccupancyUpdateCertainty = 0.7f;
    io.maxFreenessUpdateCertainty = kNaN;
    EXPECT_THROW(CRTreeOccupancyGridMap(0.1, io), std::invalid_argument) << preset;
  }
  // The same options set on a map and then used by loadFromGrid.
  mrpt::maps::COccupancyGridMap2D grid(-1.0f, 1.0f, -1.0f, 1.0f, 0.1f);
  CRTreeOccupancyGridMap m(0.1);
  m.insertionOptions.maxOccupancyUpdateCertainty = kNaN;
  EXPECT_THROW(m.loadFromGrid(grid), std::invalid_argument);
}
