// Reading a map file for the rtog commands (either format: rtog/mrpt/map_file.h), and errors in one line.
#include <utility>

#include "commands.hpp"
#include "rtog/mrpt/error_line.h"
#include "rtog/mrpt/map_file.h"

namespace rtog::cli {

std::string oneLine(const std::exception& e) { return errorLine(e); }

OccupancyMap loadMap(const std::string& path) { return std::move(loadMapFile(path)->map()); }

}  // namespace rtog::cli
