// The engine behind an OccupancyMap, for the core's own code and its tests (not installed).
#pragma once

#include "map/map_engine.hpp"
#include "rtog/core/occupancy_map.hpp"

namespace rtog {

struct MapEngineAccess {
  static MapEngine& of(OccupancyMap& map) { return *map.engine_; }
  static const MapEngine& of(const OccupancyMap& map) { return *map.engine_; }
};

}  // namespace rtog
