// A 2D range scan inserted in the mrpt_grid preset: stepped into the R-tree map as
// COccupancyGridMap2D steps its cells (see mrpt_grid.hpp). The helper of
// CRTreeOccupancyGridMap::insertGridScan, taking the map and the grid's geometry it changes.
#pragma once

#include <cstddef>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::mrpt_grid {

/// Inserts `scan` taken at `robotPose` into `map` and grows `frame` as the grid grows; false
/// (nothing changed) where the grid would insert nothing. On true, `stats` holds the counts,
/// `invalid` the invalid ranges not taken as free, and `update`, if given, what changed. A throw
/// leaves `map` and `frame` as they were.
bool insertScan(OccupancyMap& map, TGridFrame2D& frame, const mrpt::obs::CObservation2DRangeScan& scan,
                const mrpt::poses::CPose3D& robotPose, const CRTreeOccupancyGridMap::TInsertionOptions& io,
                CRTreeOccupancyGridMap::GridScanUpdate* update, InsertStats& stats, std::size_t& invalid);

}  // namespace rtog::mrpt_grid
