// Core maps as the MRPT map type: the octomap preset stating a core map's rule, wrapping a core
// map, reading a map file of either format (doc/format.md) from a file or a pipe, whole; and the
// map an .ini section defines.
#include "rtog/mrpt/map_file.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <utility>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/TMetricMapInitializer.h>

#include "gzip.hpp"
#include "rtog/mrpt/ini_checks.h"
#include "rtog/mrpt/tiled_map.h"
#include "rtog/mrpt/error_line.h"

namespace rtog {
namespace {

std::runtime_error trailing(std::uint64_t n) {
  return std::runtime_error(std::to_string(n) + " trailing byte" + (n == 1 ? "" : "s") +
                            " after the map (a damaged file, or not one map?)");
}

/// One line of what went wrong reading a map; a short stream in MRPT's words said plainly.
std::string reason(const std::exception& e) {
  const std::string s = errorLine(e);
  if (s.find("Cannot read requested number of bytes") != std::string::npos) return "truncated stream (the archive ends early)";
  return s == kNoReason ? "unreadable MRPT archive" : s;
}

/// The MRPT map type reads its own files (gzip, forward only, trailing bytes counted).
std::shared_ptr<CRTreeOccupancyGridMap> readMrptMap(std::istream& in) {
  try {
    return CRTreeOccupancyGridMap::loadFromStream(in);
  } catch (const std::exception& e) {
    throw std::runtime_error(reason(e));
  }
}

}  // namespace

RTreeInsertionOptions RTreeInsertionOptions::fromCore(const MapParams& map, const InsertParams& ip) {
  // rtog's own options state OctoMap's rule (hit/miss probabilities, clamping); an .ini states MRPT's.
  RTreeInsertionOptions io;
  io.sensorModelPreset = "octomap";
  const LogOddsParams& lp = map.log_odds;
  io.sensorModel = toString(ip.model);
  io.rangeNoiseStd = float(ip.range_noise_std);
  io.rangeNoiseStdPerMeter = float(ip.range_noise_std_per_meter);
  io.rangeNoiseCutoff = float(ip.range_noise_cutoff);
  io.rangeNoiseSharedBand = static_cast<int>(ip.range_noise_shared_band);
  io.mergePolicy = toString(map.merge);
  io.discretize = ip.discretize;
  io.threads = ip.threads;
  io.maxDistanceInsertion = ip.max_range > 0 ? float(ip.max_range) : 0.0f;
  io.maxOccupancyUpdateCertainty = float(lp.prob_hit);
  io.maxFreenessUpdateCertainty = float(1.0 - lp.prob_miss);
  io.clampingMin = float(lp.clamp_min);
  io.clampingMax = float(lp.clamp_max);
  io.occupiedThreshold = float(lp.occupied_threshold);
  return io;
}

std::shared_ptr<CRTreeOccupancyGridMap> wrapCoreMap(OccupancyMap&& map) {
  InsertParams ip;
  auto m = std::make_shared<CRTreeOccupancyGridMap>(
      map.resolution(), CRTreeOccupancyGridMap::TInsertionOptions::fromCore(map.params(), ip));
  m->map() = std::move(map);
  m->notifyMapChanged();
  return m;
}

std::shared_ptr<CRTreeOccupancyGridMap> loadMapFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw std::runtime_error("cannot open map file '" + path + "': " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) {
    if (isTiledMap(path)) return wrapCoreMap(loadTiles(path));
    throw std::runtime_error("cannot open map file '" + path + "': it is a directory (a tiled map holds " +
                             TiledMapIndex::kFile + ")");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open map file '" + path + "': " + std::strerror(errno));
  try {
    // A gzip stream is the MRPT map's own file (CRTreeOccupancyGridMap::saveToFile, as the MRPT
    // apps write it); anything else must be the core format. Peeked, not seeked: a pipe cannot.
    const int first = in.peek();
    if (first == std::char_traits<char>::eof()) throw std::runtime_error("the file is empty");
    if (gzip::startsMember(first)) return readMrptMap(in);
    OccupancyMap map = OccupancyMap::read(in);
    std::uint64_t left = 0;
    char scratch[1 << 14];
    while (in.read(scratch, sizeof(scratch)) || in.gcount() > 0) left += static_cast<std::uint64_t>(in.gcount());
    if (left) throw trailing(left);
    return wrapCoreMap(std::move(map));
  } catch (const std::exception& e) {
    throw std::runtime_error("'" + path + "': " + e.what());
  }
}

std::shared_ptr<CRTreeOccupancyGridMap> mapFromIni(const std::string& path, const std::string& section) {
  mrpt::config::CConfigFile cfg(path);
  if (!cfg.sectionExists(section)) throw std::invalid_argument("'" + path + "' has no section [" + section + "]");
  checkMapCounts(cfg, section);
  mrpt::maps::TSetOfMetricMapInitializers inits;
  inits.loadFromConfigFile(cfg, section);
  mrpt::maps::CMultiMetricMap multi;
  multi.setListOfMaps(inits);
  auto m = multi.mapByClass<CRTreeOccupancyGridMap>();
  if (!m)
    throw std::invalid_argument("section [" + section + "] of '" + path +
                                "' defines no rtreeOccupancyGrid map (add rtreeOccupancyGrid_count=1)");
  return m;
}

}  // namespace rtog
