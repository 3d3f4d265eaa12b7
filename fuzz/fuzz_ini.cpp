// libFuzzer target: `.ini` text as MRPT's apps read it (mrpt::config::CConfigFileMemory), through
// the plugin's option sections (TInsertionOptions, TLikelihoodOptions, TGridViewOptions,
// TMatchingOptions) and map definitions (the CMultiMetricMap sections that create a
// CRTreeOccupancyGridMap or CRTreeBackedGridMap2D). A bad value must be an exception naming it;
// a map created from accepted values must work (a short fixed scan is inserted and scored).
#include <strings.h>

#include <cmath>
#include <cstdint>
#include <exception>
#include <stdexcept>
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/TMetricMapInitializer.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/mrpt/CRTreeBackedGridMap2D.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/ini_checks.h"
#include "rtog/mrpt/register_classes.h"
#include "null_stderr.hpp"

namespace {

using rtog::CRTreeOccupancyGridMap;

// Bounds that keep one input fast; a large input is no more interesting than a small one here.
constexpr std::size_t kMaxSections = 8;
constexpr std::size_t kMaxMaps = 4;
// Our maps' initial 2D grid (min_x..max_x by min_y..max_y, default 20 m square) is cut to this
// half-width about the origin before the map is made: the fixed scan reaches 2.5 m and the grid
// grows to hold it, as COccupancyGridMap2D's does. A full-size grid is zero-filled by MRPT and
// again by the view's likelihood field for every map, which held the target to about 150 inputs
// per second (and a 1 mm grid to far fewer). The size limits themselves are fuzzed by
// rtog_fuzz_insert and tested in tests/mrpt.
constexpr float kMaxHalfWidth = 3.0f;
// And a valid resolution finer than this is raised to it: a 1 mm map makes 36 M cells of a 6 m grid
// and a view 15 m across for its scan, both zero-filled (p99 of a grown corpus: 0.1 s). Bad values (zero,
// negative, NaN) still reach the map's checks.
constexpr double kMinResolution = 0.05;

template <class Def>
void cutExtent(Def& d) {
  if (d.resolution > 0.0 && d.resolution < kMinResolution) d.resolution = kMinResolution;
  // Only a valid extent: a bad one (NaN, reversed) must still reach the map's own checks.
  if (!(d.min_x < d.max_x && d.min_y < d.max_y)) return;
  d.min_x = std::max(d.min_x, -kMaxHalfWidth), d.max_x = std::min(d.max_x, kMaxHalfWidth);
  d.min_y = std::max(d.min_y, -kMaxHalfWidth), d.max_y = std::min(d.max_y, kMaxHalfWidth);
  if (!(d.min_x < d.max_x)) d.min_x = -kMaxHalfWidth, d.max_x = kMaxHalfWidth;  // wholly beyond it
  if (!(d.min_y < d.max_y)) d.min_y = -kMaxHalfWidth, d.max_y = kMaxHalfWidth;
}

/// Cuts the extent of one of our definitions; false for a stock map's.
bool ourDefinitionCut(mrpt::maps::TMetricMapInitializer& def) {
  if (auto* d = dynamic_cast<CRTreeOccupancyGridMap::TMapDefinition*>(&def)) return cutExtent(*d), true;
  if (auto* d = dynamic_cast<rtog::CRTreeBackedGridMap2D::TMapDefinition*>(&def)) return cutExtent(*d), true;
  return false;
}

template <class Options>
void loadSection(const mrpt::config::CConfigFileBase& cfg, const std::string& sec) {
  Options o;
  try {
    o.loadFromConfigFile(cfg, sec);
  } catch (const std::exception&) {
    return;
  }
  // Accepted values write themselves out and are read again (the dump a user gets back).
  mrpt::config::CConfigFileMemory out;
  o.saveToConfigFile(out, sec);
  Options again;
  try {
    again.loadFromConfigFile(out, sec);
  } catch (const std::exception&) {
  }
}

mrpt::obs::CObservation2DRangeScan fixedScan() {
  mrpt::obs::CObservation2DRangeScan s;
  s.aperture = static_cast<float>(M_PI);
  s.maxRange = 10.0f;
  s.resizeScan(9);
  for (std::size_t i = 0; i < 9; ++i) {
    s.setScanRange(i, 0.5f + 0.25f * static_cast<float>(i));
    s.setScanRangeValidity(i, true);
  }
  return s;
}

void useMap(mrpt::maps::CMetricMap& m) {
  static const auto scan = fixedScan();
  const mrpt::poses::CPose3D pose(0.1, 0.2, 0.0, 0.3, 0.0, 0.0);
  m.insertObservation(scan, pose);
  (void)m.computeObservationLikelihood(scan, pose);
  (void)m.isEmpty();
}

/// Case-insensitive, as MRPT's section names.
bool endsWith(const std::string& s, const char* tail) {
  const std::size_t n = std::char_traits<char>::length(tail);
  return s.size() >= n && strcasecmp(s.c_str() + s.size() - n, tail) == 0;
}

/// Whether the section has a key "*_count" (a CMultiMetricMap definition).
bool countsMaps(const mrpt::config::CConfigFileBase& cfg, const std::string& sec) {
  std::vector<std::string> keys;
  cfg.getAllKeys(sec, keys);
  for (const std::string& key : keys)
    if (endsWith(key, "_count")) return true;
  return false;
}

bool isOurMapCount(const std::string& key) {
  for (const char* name : {"rtreeOccupancyGrid_count", "rtog::CRTreeOccupancyGridMap_count", "rtreeGridMap2D_count",
                           "rtog::CRTreeBackedGridMap2D_count"})
    if (strcasecmp(key.c_str(), name) == 0) return true;
  return false;
}

// The configuration as MRPT's readers see it, with every stock map's count read as 0. MRPT 2.5.8's
// TSetOfMetricMapInitializers holds a new definition by raw pointer while its loadFromConfigFile
// runs, so a stock map's loader that throws on a bad value (e.g. COccupancyGridMap2D's
// likelihoodMethod) leaks it: MRPT's code, not ours. Our own definitions keep a load error and
// raise it at creation for that reason. A view, not a copy: a copy would run MRPT's preprocessor
// over the text again, which was the largest part of an input's time.
class OurMapsOnly : public mrpt::config::CConfigFileBase {
 public:
  explicit OurMapsOnly(const mrpt::config::CConfigFileBase& all) : all_(all) {}
  void getAllSections(std::vector<std::string>& sections) const override { all_.getAllSections(sections); }
  void getAllKeys(const std::string& section, std::vector<std::string>& keys) const override {
    all_.getAllKeys(section, keys);
  }
  void clear() override { throw std::logic_error("OurMapsOnly is read-only"); }

 protected:
  void writeString(const std::string&, const std::string&, const std::string&) override {
    throw std::logic_error("OurMapsOnly is read-only");
  }
  std::string readString(const std::string& section, const std::string& name, const std::string& def,
                         bool failIfNotFound) const override {
    if (endsWith(name, "_count") && !isOurMapCount(name)) return "0";  // MRPT reads counts with default 0
    return all_.read_string(section, name, def, failIfNotFound);
  }

 private:
  const mrpt::config::CConfigFileBase& all_;
};

void createMaps(const mrpt::config::CConfigFileBase& all, const std::string& sec) {
  mrpt::maps::TSetOfMetricMapInitializers inits;
  try {
    rtog::checkMapCounts(all, sec);  // as rtog build does: MRPT reads "-1" as four billion maps
    inits.loadFromConfigFile(OurMapsOnly(all), sec);
  } catch (const std::exception&) {
    return;
  }
  std::size_t made = 0;
  for (auto& def : inits) {
    if (!ourDefinitionCut(*def) || made++ == kMaxMaps) continue;
    std::unique_ptr<mrpt::maps::CMetricMap> m;
    try {
      m.reset(mrpt::maps::internal::TMetricMapTypesRegistry::Instance().factoryMapObjectFromDefinition(*def));
    } catch (const std::exception&) {
      continue;  // a bad value, reported
    }
    if (!m) continue;
    try {
      useMap(*m);
    } catch (const std::exception&) {
      // Some accepted option sets refuse some observations (e.g. a tilted scan): a clear error.
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rtog::registerMrptClasses();
  rtog_fuzz::discardStdErr();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  mrpt::config::CConfigFileMemory cfg;
  try {
    cfg.setContent(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const std::exception&) {
    return 0;  // MRPT's parser refuses the text (e.g. an unclosed ${...}): not the plugin's code
  }
  std::vector<std::string> sections;
  cfg.getAllSections(sections);
  if (sections.size() > kMaxSections) sections.resize(kMaxSections);
  // Each section as MRPT's apps read it: options from the sections named for them (rtog build
  // and the map definitions use *_insertOpts, *_likelihoodOpts, *_creationOpts, *_matchingOpts),
  // map definitions from a section that counts maps. Every reader on every section took four
  // times the work for the same code: MRPT's readers format each default into a 2 KiB string.
  for (const auto& sec : sections) {
    if (endsWith(sec, "insertOpts")) loadSection<CRTreeOccupancyGridMap::TInsertionOptions>(cfg, sec);
    if (endsWith(sec, "likelihoodOpts")) loadSection<CRTreeOccupancyGridMap::TLikelihoodOptions>(cfg, sec);
    if (endsWith(sec, "creationOpts")) loadSection<CRTreeOccupancyGridMap::TGridViewOptions>(cfg, sec);
    if (endsWith(sec, "matchingOpts")) loadSection<CRTreeOccupancyGridMap::TMatchingOptions>(cfg, sec);
    if (countsMaps(cfg, sec)) createMaps(cfg, sec);
  }
  // As in rtog_fuzz_insert: buffers kept for the next map would make libFuzzer run a leak pass.
  rtog::OccupancyMap::releaseInsertBuffers();
  return 0;
}
