// Shared helpers of the MRPT map tests: real rawlogs from Debian's mrpt-common.
#pragma once

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog_test {

inline std::string dataset(const std::string& name) { return std::string(RTOG_MRPT_DATASETS) + "/" + name; }
/// The maps MRPT's map loader makes (as MRPT's apps do) from the `[MappingApplication]` sections
/// of `ini`.
inline mrpt::maps::CMultiMetricMap multiMapFromIni(const std::string& ini) {
  mrpt::config::CConfigFileMemory cfg(ini);
  mrpt::maps::TSetOfMetricMapInitializers inits;
  inits.loadFromConfigFile(cfg, "MappingApplication");
  mrpt::maps::CMultiMetricMap mm;
  mm.setListOfMaps(inits);
  return mm;
}
/// A CRTreeOccupancyGridMap made by MRPT's map loader (as MRPT's apps create maps) from an `.ini`
/// whose `_creationOpts` section holds `creation` and whose `_insertOpts` section holds `insert_opts`.
inline rtog::CRTreeOccupancyGridMap::Ptr mapFromSections(const std::string& creation, const std::string& insert_opts) {
  const std::string ini = "[MappingApplication]\nrtreeOccupancyGrid_count=1\n"
                          "[MappingApplication_rtreeOccupancyGrid_00_creationOpts]\n" + creation +
                          "\n[MappingApplication_rtreeOccupancyGrid_00_insertOpts]\n" + insert_opts + "\n";
  return std::dynamic_pointer_cast<rtog::CRTreeOccupancyGridMap>(multiMapFromIni(ini).maps.at(0));
}
/// The same at 5 cm.
inline rtog::CRTreeOccupancyGridMap::Ptr mapFromIni(const std::string& insert_opts) {
  return mapFromSections("resolution=0.05", insert_opts);
}

inline const std::string kSena = "2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";

struct PosedFrame {
  mrpt::poses::CPose3D pose;
  mrpt::obs::CSensoryFrame::Ptr sf;
};

/// Sensory frames of an action/observation rawlog with the odometry-integrated robot pose.
inline std::vector<PosedFrame> loadOdometryFrames(const std::string& file, std::size_t max_frames = 1u << 30) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(file)) throw std::runtime_error("cannot load " + file);
  std::vector<PosedFrame> out;
  mrpt::poses::CPose2D pose;
  for (std::size_t i = 0; i < rl.size() && out.size() < max_frames; ++i) {
    if (rl.getType(i) == mrpt::obs::CRawlog::etActionCollection) {
      auto acts = rl.getAsAction(i);
      mrpt::poses::CPose3D inc;
      if (acts->getFirstMovementEstimationMean(inc)) pose = pose + mrpt::poses::CPose2D(inc);
    } else if (rl.getType(i) == mrpt::obs::CRawlog::etSensoryFrame) {
      out.push_back({mrpt::poses::CPose3D(pose), rl.getAsObservations(i)});
    }
  }
  return out;
}

/// The first observation of an observation-only rawlog.
inline mrpt::obs::CObservation::Ptr firstObservation(const std::string& file) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(file)) throw std::runtime_error("cannot load " + file);
  for (std::size_t i = 0; i < rl.size(); ++i)
    if (rl.getType(i) == mrpt::obs::CRawlog::etObservation) return rl.getAsObservation(i);
  throw std::runtime_error("no observation in " + file);
}

/// The smallest and largest int8 cell that the maps `alone` (cell key -> value; a missing cell is
/// 0, the grids' unknown) hold at `key`: the range a mixture of them must lie in.
template <class Maps, class K>
std::pair<int, int> cellRange(const Maps& alone, const K& key) {
  int lo = 127, hi = -127;
  for (const auto& a : alone) {
    const auto it = a.find(key);
    const int v = it == a.end() ? 0 : it->second;
    lo = std::min(lo, v), hi = std::max(hi, v);
  }
  return {lo, hi};
}

}  // namespace rtog_test
