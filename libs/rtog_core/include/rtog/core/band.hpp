// What a 2D view of a height band shows: each (x, y) column's highest log-odds over the band's
// z-layers. MRPT's grids, the planner and the image operations all draw the band by this one rule.
#pragma once

#include <cstdint>
#include <functional>

#include "rtog/core/key.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

/// The most columns of one tile: 4 MiB of floats. A view over a sparse map's wide bounding box
/// is dense; its maxima are not held for all of it at once.
constexpr std::int64_t kBandTileColumns = std::int64_t{1} << 20;

/// The cells of `columns`' (x, y) rectangle over the z-layers whose interval [k*res, (k+1)*res)
/// meets [zmin, zmax] [m], cut to the map's known z-range: empty if the band holds no known cell
/// (or the map none, or zmin > zmax).
Box bandRegion(const OccupancyMap& m, const Box& columns, double zmin, double zmax);

/// The highest log-odds of each (x, y) column of `region` over its z-range. Given to
/// `f(y, x0, x1, best)` run by run: best[i] is column (x0 + i, y)'s, NaN where no cell is known
/// within a run; columns outside every run hold no known cell. Runs are found a tile of at most
/// kBandTileColumns columns at a time, so that a wide view of a sparse map costs its known
/// columns, not its area.
void forEachBandRun(const OccupancyMap& m, const Box& region,
                    const std::function<void(std::int32_t y, std::int32_t x0, std::int32_t x1, const float* best)>& f);

}  // namespace rtog
