// Map files of either format: the MRPT map's own (a gzip CArchive, CRTreeOccupancyGridMap::saveToFile,
// as MRPT's apps write it) and the core's (OccupancyMap::write, as `rtog build` writes it).
#pragma once

#include <memory>
#include <string>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

/// Reads a map file of either format, told apart by its first byte (peeked: a pipe works),
/// whole: trailing bytes after the map are an error; or a tiled map's directory (tiled_map.h),
/// every tile. An MRPT file gives the map with its options;
/// a core file the map wrapped as wrapCoreMap() does. Throws std::runtime_error naming the file,
/// with one line saying what is wrong (missing, a directory, empty, truncated, corrupt).
std::shared_ptr<CRTreeOccupancyGridMap> loadMapFile(const std::string& path);

/// A core map as the MRPT map type: the octomap preset stating its parameters
/// (TInsertionOptions::fromCore), the map's cells and exact parameters kept. Insertions through
/// the core (map().insert...) keep them; MRPT's insertObservation() syncs the map to its options
/// first, which throws if the float options cannot state the map's double parameters exactly.
std::shared_ptr<CRTreeOccupancyGridMap> wrapCoreMap(OccupancyMap&& map);

/// The rtreeOccupancyGrid map that section `section` of the .ini file `path` defines (as a
/// CMultiMetricMap reads it, rtreeOccupancyGrid_count=1 with its _creationOpts, _insertOpts...).
/// Throws std::invalid_argument for a missing section, map counts other than one, bad options.
std::shared_ptr<CRTreeOccupancyGridMap> mapFromIni(const std::string& path, const std::string& section);

}  // namespace rtog
