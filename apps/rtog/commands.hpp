// The rtog tool's commands, callable from tests; main.cpp only parses arguments.
#pragma once

#include <iosfwd>
#include <string>

#include "rtog/core/occupancy_map.hpp"

namespace rtog::cli {

struct BuildTumOptions {
  std::string tum_dir;      ///< directory with groundtruth_poses.txt and depth/
  std::string out_path;     ///< .rtog file to write; empty: do not save
  MapParams map;            ///< resolution, log-odds, merging
  InsertParams insert;      ///< sensor model, max range
  int stride = 1;           ///< use every stride-th pixel in each direction (Default: 1)
};

/// Builds a map from a TUM depth sequence, prints progress and a summary to `out`.
/// Returns the process exit code.
int buildFromTum(const BuildTumOptions& opts, std::ostream& out);

/// Prints a saved map's statistics (plain or JSON). Returns the process exit code.
int info(const std::string& map_path, bool json, std::ostream& out);

void printStatistics(const OccupancyMap& map, std::ostream& out);

/// Loads a .rtog map; throws std::runtime_error naming the file on failure.
OccupancyMap loadMap(const std::string& path);
/// Saves atomically (temporary file, then rename): nothing half-written on failure.
void saveMap(const OccupancyMap& map, const std::string& path);

}  // namespace rtog::cli
