// rtog::CRTreeOccupancyGridMap: prior maps (doc/priors.md), a blueprint image or a .gridmap as the
// first layer, trusted to a stated confidence; its options (TPriorMapOptions).
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/maps/COccupancyGridMap2D.h>

#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "options_check.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

namespace {
[[noreturn]] void bad(const std::string& key, const std::string& why) {
  throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: invalid option [creationOpts] " + key + ": " + why);
}
bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
}  // namespace

void TPriorMapOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& s, const std::string& sec) {
  priorMap = s.read_string(sec, "priorMap", priorMap);
  priorConfidence = readDouble(s, sec, "priorConfidence", priorConfidence);
  priorResolution = readDouble(s, sec, "priorResolution", priorResolution);
  priorOriginX = readDouble(s, sec, "priorOriginX", priorOriginX);
  priorOriginY = readDouble(s, sec, "priorOriginY", priorOriginY);
  validateInSection(sec, [this] { validate(); });
  const bool gridmap = isGridmap();
  for (const char* k : {"priorConfidence", "priorResolution", "priorOriginX", "priorOriginY"}) {
    if (!s.keyExists(sec, k)) continue;
    if (priorMap.empty()) reportInertKey(sec, k, "no priorMap is set");
    else if (gridmap && k != std::string("priorConfidence"))
      reportInertKey(sec, k, "a .gridmap prior has its own geometry (" + std::string(k) + " is for an image)");
  }
}

void TPriorMapOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& sec) const {
  c.write(sec, "priorMap", priorMap);
  c.write(sec, "priorConfidence", priorConfidence);
  c.write(sec, "priorResolution", priorResolution);
  c.write(sec, "priorOriginX", priorOriginX);
  c.write(sec, "priorOriginY", priorOriginY);
}

void TPriorMapOptions::validate() const {
  if (!(priorConfidence > 0.5 && priorConfidence <= 1.0))
    bad("priorConfidence", "must lie in (0.5, 1], got " + std::to_string(priorConfidence));
  if (!(std::isfinite(priorResolution) && priorResolution >= 1e-4 && priorResolution <= 1e3))
    bad("priorResolution", "must lie in [1e-4, 1e3] m, got " + std::to_string(priorResolution));
  // Within the key range of the finest lattice (52 km at 5 cm): beyond it no cell could hold it.
  for (const auto& [key, v] : {std::pair{"priorOriginX", priorOriginX}, std::pair{"priorOriginY", priorOriginY}})
    if (!(std::isfinite(v) && std::fabs(v) <= 1e6)) bad(key, "must be a finite coordinate within 1e6 m, got " + std::to_string(v));
}

bool TPriorMapOptions::isGridmap() const { return endsWith(priorMap, ".gridmap") || endsWith(priorMap, ".gridmap.gz"); }

void CRTreeOccupancyGridMap::loadPrior(const TPriorMapOptions& o) {
  o.validate();
  if (o.priorMap.empty()) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap::loadPrior: no priorMap file given");
  const std::string& f = o.priorMap;
  if (!std::ifstream(f, std::ios::binary).good())
    throw std::runtime_error("prior map '" + f + "': cannot open it (missing or unreadable)");
  mrpt::maps::COccupancyGridMap2D grid;
  if (o.isGridmap()) {
    if (!readGridmapFile(f, grid))
      throw std::runtime_error("prior map '" + f + "': not a serialized COccupancyGridMap2D (.gridmap[.gz])");
  } else {
    // MRPT's origin is the pixel at map (0, 0), counted from the lower-left corner.
    const double px = -o.priorOriginX / o.priorResolution, py = -o.priorOriginY / o.priorResolution;
    if (!grid.loadFromBitmapFile(f, static_cast<float>(o.priorResolution), mrpt::math::TPoint2D(px, py)))
      throw std::runtime_error("prior map '" + f + "': not an image MRPT can read (PNG, JPEG, BMP, ...)");
  }
  loadPrior(grid, o.priorConfidence);
}

}  // namespace rtog
