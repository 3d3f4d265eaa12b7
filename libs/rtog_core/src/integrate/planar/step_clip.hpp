// A grid's ordered steps (StepRun) restricted to the bricks a map owns (OccupancyMap::setRegion).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "rtog/core/log_odds.hpp"
#include "storage/map_store.hpp"

namespace rtog {

/// The steps of runs[0, n) on z-layer `z` whose cells lie in bricks the map owns, in their order:
/// a run wholly inside is kept, one wholly outside dropped, one across the border cut to the
/// steps inside (an interval: the raster is monotone on each axis), the same raster from a later
/// step (StepRun::skip). kept[i]
/// says whether step i of forEachRunCell's order was kept. Throws std::out_of_range, as
/// OccupancyMap::applyStepRuns does, for a cell outside the key range, kept or not.
void clipStepRuns(const MapStore& store, std::int32_t z, const StepRun* runs, std::size_t n, std::vector<StepRun>& out,
                  std::vector<std::uint8_t>& kept);

}  // namespace rtog
