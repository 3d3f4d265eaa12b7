// libFuzzer target: `.ini` text as MRPT's apps read it (mrpt::config::CConfigFileMemory), through
// the plugin's option sections (TInsertionOptions, TLikelihoodOptions, TGridViewOptions,
// TMatchingOptions) and map definitions (the CMultiMetricMap sections that create a
// CRTreeOccupancyGridMap or CRTreeBackedGridMap2D). A bad value must be an exception naming it;
// a map created from accepted values must work (a short fixed scan is inserted and scored).
#include <strings.h>

#include <cmath>
#include <cstdint>
#include <exception>
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

bool isOurMapCount(const std::string& key) {
  for (const char* name : {"rtreeOccupancyGrid_count", "rtog::CRTreeOccupancyGridMap_count", "rtreeGridMap2D_count",
                           "rtog::CRTreeBackedGridMap2D_count"})
    if (strcasecmp(key.c_str(), name) == 0) return true;
  return false;
}

// The section with every stock map's count set to 0. MRPT 2.5.8's TSetOfMetricMapInitializers holds
// a new definition by raw pointer while its loadFromConfigFile runs, so a stock map's loader that
// throws on a bad value (e.g. COccupancyGridMap2D's likelihoodMethod) leaks it: MRPT's code, not
// ours. Our own definitions keep a load error and raise it at creation for that reason.
mrpt::config::CConfigFileMemory withOurMapsOnly(const mrpt::config::CConfigFileMemory& cfg, const std::string& sec) {
  std::string text;
  cfg.getContent(text);
  mrpt::config::CConfigFileMemory ours(text);
  std::vector<std::string> keys;
  ours.getAllKeys(sec, keys);
  for (const std::string& key : keys)
    if (key.size() > 6 && strcasecmp(key.c_str() + key.size() - 6, "_count") == 0 && !isOurMapCount(key))
      ours.write(sec, key, 0);
  return ours;
}

void createMaps(const mrpt::config::CConfigFileMemory& all, const std::string& sec) {
  mrpt::maps::TSetOfMetricMapInitializers inits;
  try {
    rtog::checkMapCounts(all, sec);  // as rtog build does: MRPT reads "-1" as four billion maps
    inits.loadFromConfigFile(withOurMapsOnly(all, sec), sec);
  } catch (const std::exception&) {
    return;
  }
  std::size_t made = 0;
  for (const auto& def : inits) {
    const bool ours = dynamic_cast<const CRTreeOccupancyGridMap::TMapDefinition*>(def.get()) ||
                      dynamic_cast<const rtog::CRTreeBackedGridMap2D::TMapDefinition*>(def.get());
    if (!ours || made++ == kMaxMaps) continue;
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
  for (const auto& sec : sections) {
    loadSection<CRTreeOccupancyGridMap::TInsertionOptions>(cfg, sec);
    loadSection<CRTreeOccupancyGridMap::TLikelihoodOptions>(cfg, sec);
    loadSection<CRTreeOccupancyGridMap::TGridViewOptions>(cfg, sec);
    loadSection<CRTreeOccupancyGridMap::TMatchingOptions>(cfg, sec);
    createMaps(cfg, sec);
  }
  // As in rtog_fuzz_insert: buffers kept for the next map would make libFuzzer run a leak pass.
  rtog::OccupancyMap::releaseInsertBuffers();
  return 0;
}
