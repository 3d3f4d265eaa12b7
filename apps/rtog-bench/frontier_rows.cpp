// The frontier row: the 2D frontier of a built map, from rtog's cuboids (rtog::frontierCells over
// the band) and by a dense scan of MRPT's grid, as an explorer on COccupancyGridMap2D finds it (each
// cell against its four neighbours). Median of 9 runs.
#include <chrono>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>

#include "bench.hpp"
#include "rtog/core/explore.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::bench {
namespace {

using Clock = std::chrono::steady_clock;

std::size_t denseFrontier(const mrpt::maps::COccupancyGridMap2D& g) {
  // The grid's raw cells: 0 is unknown (P = 0.5), a positive cell free (P < 0.5).
  const auto& raw = g.getRawMap();
  const int w = static_cast<int>(g.getSizeX()), h = static_cast<int>(g.getSizeY());
  std::size_t n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const auto c = raw[static_cast<std::size_t>(y * w + x)];
      if (c <= 0) continue;
      const auto unknown = [&](int xx, int yy) {
        return xx >= 0 && yy >= 0 && xx < w && yy < h && raw[static_cast<std::size_t>(yy * w + xx)] == 0;
      };
      n += unknown(x - 1, y) || unknown(x + 1, y) || unknown(x, y - 1) || unknown(x, y + 1);
    }
  return n;
}

}  // namespace

void measureFrontiers(const mrpt::maps::CMetricMap& map, Result& r) {
  std::size_t cells = 0;
  std::vector<double> runs;
  for (int run = 0; run < 9; ++run) {
    const auto t0 = Clock::now();
    if (const auto* g = dynamic_cast<const mrpt::maps::COccupancyGridMap2D*>(&map)) {
      cells = denseFrontier(*g);
    } else if (const auto* m = dynamic_cast<const CRTreeOccupancyGridMap*>(&map)) {
      FrontierOptions o;
      o.planar = true;
      cells = 0;
      for (const Box& b : frontierCells(m->map(), o)) cells += static_cast<std::size_t>(b.extent(0));
    } else {
      return;
    }
    runs.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  r.extra["frontier_ms"] = median(runs) * 1e3;
  r.extra["frontier_cells"] = double(cells);
}

}  // namespace rtog::bench
