// rtog::CRTreeOccupancyGridMap: the .ini side — TInsertionOptions, TLikelihoodOptions,
// TGridViewOptions, TMatchingOptions and TMapDefinition (read, written, validated by key).
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/core/bits_math.h>

#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "mrpt_grid.hpp"
#include "mrpt_grid3d.hpp"
#include "options_check.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

namespace {
[[noreturn]] void badOption(const std::string& section, const std::string& key, const std::string& why) {
  throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: invalid option [" + section + "] " + key + ": " + why);
}
bool isProbability(float p) { return std::isfinite(p) && p > 0.0f && p < 1.0f; }
/// Keys of the section that the other options make inert: told once (reportInertKey), as
/// unknown keys are, for a value that would otherwise be dropped without a word.
void reportInertInsertKeys(const RTreeInsertionOptions& o, const mrpt::config::CConfigFileBase& s,
                           const std::string& sec) {
  const auto told = [&](std::initializer_list<const char*> keys, const std::string& why) {
    for (const char* k : keys)
      if (s.keyExists(sec, k)) reportInertKey(sec, k, why);
  };
  if (sensorModelFromString(o.sensorModel) != SensorModel::RangeNoise)
    told({"rangeNoiseStd", "rangeNoiseStdPerMeter", "rangeNoiseCutoff", "rangeNoiseSharedBand"},
         "only sensorModel = rangeNoise uses it (sensorModel is " + o.sensorModel + ")");
  if (o.mrptGrid())
    told({"clampingMin", "clampingMax"},
         "the mrpt_grid preset saturates at the grid's int8 range; only sensorModelPreset = octomap clamps there");
  // A stock section's mapAltitude = 0 beside useMapAltitude = 0 states nothing; another altitude does.
  if (!o.useMapAltitude && o.mapAltitude != 0.0f) told({"mapAltitude"}, "only useMapAltitude = true uses it");
}
}  // namespace

// ---- TInsertionOptions -------------------------------------------------------------------

void CRTreeOccupancyGridMap::TInsertionOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& s,
                                                                  const std::string& sec) {
  sensorModelPreset = s.read_string(sec, "sensorModelPreset", sensorModelPreset);
  sensorModel = s.read_string(sec, "sensorModel", sensorModel);
  rangeNoiseStd = readFloat(s, sec, "rangeNoiseStd", rangeNoiseStd);
  rangeNoiseStdPerMeter = readFloat(s, sec, "rangeNoiseStdPerMeter", rangeNoiseStdPerMeter);
  rangeNoiseCutoff = readFloat(s, sec, "rangeNoiseCutoff", rangeNoiseCutoff);
  rangeNoiseSharedBand = readInt(s, sec, "rangeNoiseSharedBand", rangeNoiseSharedBand);
  maxOccupancyUpdateCertainty = readFloat(s, sec, "maxOccupancyUpdateCertainty", maxOccupancyUpdateCertainty);
  maxFreenessUpdateCertainty = readFloat(s, sec, "maxFreenessUpdateCertainty", maxFreenessUpdateCertainty);
  // Read as 0 where absent: a section without them states the sensor by the certainties.
  missRate = readFloat(s, sec, "missRate", 0.0f);
  falseAlarmRate = readFloat(s, sec, "falseAlarmRate", 0.0f);
  if (missRate != 0.0f || falseAlarmRate != 0.0f) {
    // The sensor stated as a channel: the certainties follow from it, so they may not be given too.
    for (const char* k : {"maxOccupancyUpdateCertainty", "maxFreenessUpdateCertainty"})
      if (s.keyExists(sec, k))
        badOption(sec, "missRate/falseAlarmRate",
                  std::string("state the sensor by the rates or by the certainties, not both (") + k + " is set)");
    applySensorChannel(sec);
  }
  maxFreenessInvalidRanges = readFloat(s, sec, "maxFreenessInvalidRanges", maxFreenessInvalidRanges);
  considerInvalidRangesAsFreeSpace =
      readBool(s, sec, "considerInvalidRangesAsFreeSpace", considerInvalidRangesAsFreeSpace);
  horizontalTolerance = mrpt::DEG2RAD(readFloat(s, sec, "horizontalTolerance", mrpt::RAD2DEG(horizontalTolerance)));
  useMapAltitude = readBool(s, sec, "useMapAltitude", useMapAltitude);
  mapAltitude = readFloat(s, sec, "mapAltitude", mapAltitude);
  wideningBeamsWithDistance = readBool(s, sec, "wideningBeamsWithDistance", wideningBeamsWithDistance);
  clampingMin = readFloat(s, sec, "clampingMin", clampingMin);
  clampingMax = readFloat(s, sec, "clampingMax", clampingMax);
  occupiedThreshold = readFloat(s, sec, "occupiedThreshold", occupiedThreshold);
  maxDistanceInsertion = readFloat(s, sec, "maxDistanceInsertion", maxDistanceInsertion);
  const int dec = readInt(s, sec, "decimation", decimation);
  const int dec3 = readInt(s, sec, "decimation_3d_range", decimation_3d_range);
  if (dec < 1 || dec > 65535) badOption(sec, "decimation", "must be an integer in [1, 65535], got " + std::to_string(dec));
  if (dec3 < 1 || dec3 > 255)
    badOption(sec, "decimation_3d_range", "must be an integer in [1, 255], got " + std::to_string(dec3));
  decimation = static_cast<uint16_t>(dec);
  decimation_3d_range = static_cast<uint16_t>(dec3);
  mergePolicy = s.read_string(sec, "mergePolicy", mergePolicy);
  discretize = readBool(s, sec, "discretize", discretize);
  threads = readInt(s, sec, "threads", threads);
  planarCache = readBool(s, sec, "planarCache", planarCache);
  maxScanCells = readDouble(s, sec, "maxScanCells", maxScanCells);
  rotatingScan_minElevation_deg = readFloat(s, sec, "rotatingScan_minElevation_deg", rotatingScan_minElevation_deg);
  rotatingScan_maxElevation_deg = readFloat(s, sec, "rotatingScan_maxElevation_deg", rotatingScan_maxElevation_deg);
  poseUncertainty = readBool(s, sec, "poseUncertainty", poseUncertainty);
  sonarConeWeighting = s.read_string(sec, "sonarConeWeighting", sonarConeWeighting);
  // COccupancyGridMap2D's keys that concern what rtog does not build (its CFD features).
  reportUnknownKeys(s, sec,
                    {"sensorModelPreset", "sensorModel", "rangeNoiseStd", "rangeNoiseStdPerMeter", "rangeNoiseCutoff", "rangeNoiseSharedBand",
                     "maxOccupancyUpdateCertainty", "maxFreenessUpdateCertainty", "missRate", "falseAlarmRate",
                     "maxFreenessInvalidRanges", "considerInvalidRangesAsFreeSpace", "horizontalTolerance",
                     "useMapAltitude", "mapAltitude", "wideningBeamsWithDistance", "clampingMin", "clampingMax",
                     "occupiedThreshold", "maxDistanceInsertion", "decimation", "decimation_3d_range", "mergePolicy",
                     "discretize", "threads", "planarCache", "rotatingScan_minElevation_deg",
                     "maxScanCells",
                     "rotatingScan_maxElevation_deg", "poseUncertainty", "sonarConeWeighting", "CFD_features_gaussian_size", "CFD_features_median_size"});
  validateInSection(sec, [this] { validate(); });
  reportInertInsertKeys(*this, s, sec);
}

void CRTreeOccupancyGridMap::TInsertionOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c,
                                                                const std::string& sec) const {
  c.write(sec, "sensorModelPreset", sensorModelPreset);
  c.write(sec, "sensorModel", sensorModel);
  c.write(sec, "rangeNoiseStd", rangeNoiseStd);
  c.write(sec, "rangeNoiseStdPerMeter", rangeNoiseStdPerMeter);
  c.write(sec, "rangeNoiseCutoff", rangeNoiseCutoff);
  c.write(sec, "rangeNoiseSharedBand", rangeNoiseSharedBand);
  c.write(sec, "maxFreenessInvalidRanges", maxFreenessInvalidRanges);
  c.write(sec, "considerInvalidRangesAsFreeSpace", considerInvalidRangesAsFreeSpace);
  c.write(sec, "horizontalTolerance", mrpt::RAD2DEG(horizontalTolerance));
  c.write(sec, "useMapAltitude", useMapAltitude);
  c.write(sec, "mapAltitude", mapAltitude);
  c.write(sec, "wideningBeamsWithDistance", wideningBeamsWithDistance);
  if (missRate != 0.0f || falseAlarmRate != 0.0f) {  // read back, the rates give these certainties
    c.write(sec, "missRate", missRate);
    c.write(sec, "falseAlarmRate", falseAlarmRate);
  } else {
    c.write(sec, "maxOccupancyUpdateCertainty", maxOccupancyUpdateCertainty);
    c.write(sec, "maxFreenessUpdateCertainty", maxFreenessUpdateCertainty);
  }
  c.write(sec, "clampingMin", clampingMin);
  c.write(sec, "clampingMax", clampingMax);
  c.write(sec, "occupiedThreshold", occupiedThreshold);
  c.write(sec, "maxDistanceInsertion", maxDistanceInsertion);
  c.write(sec, "decimation", static_cast<int>(decimation));
  c.write(sec, "decimation_3d_range", static_cast<int>(decimation_3d_range));
  c.write(sec, "mergePolicy", mergePolicy);
  c.write(sec, "discretize", discretize);
  c.write(sec, "threads", threads);
  c.write(sec, "planarCache", planarCache);
  c.write(sec, "maxScanCells", std::to_string(static_cast<std::uint64_t>(maxScanCells)));  // whole: "%e" would round it
  if (!std::isnan(rotatingScan_minElevation_deg)) {  // unset is no key: a written "nan" may not read back
    c.write(sec, "rotatingScan_minElevation_deg", rotatingScan_minElevation_deg);
    c.write(sec, "rotatingScan_maxElevation_deg", rotatingScan_maxElevation_deg);
  }
  c.write(sec, "poseUncertainty", poseUncertainty ? "on" : "off");
  c.write(sec, "sonarConeWeighting", sonarConeWeighting);
}

void CRTreeOccupancyGridMap::TInsertionOptions::applySensorChannel(const std::string& sec) {
  if (!(std::isfinite(missRate) && std::isfinite(falseAlarmRate) && missRate > 0.0f && falseAlarmRate > 0.0f))
    badOption(sec, "missRate/falseAlarmRate", "set both, each in (0, 1), or neither; got " + std::to_string(missRate) +
                                                  " and " + std::to_string(falseAlarmRate));
  LogOddsParams p;
  try {
    p = withChannel(p, SensorChannel{missRate, falseAlarmRate});
  } catch (const std::invalid_argument& e) {
    badOption(sec, "missRate/falseAlarmRate", e.what());
  }
  maxOccupancyUpdateCertainty = static_cast<float>(p.prob_hit);
  maxFreenessUpdateCertainty = static_cast<float>(1.0 - p.prob_miss);
}

InsertParams CRTreeOccupancyGridMap::TInsertionOptions::toInsertParams() const {
  InsertParams ip;
  ip.model = sensorModelFromString(sensorModel);
  ip.max_range = maxDistanceInsertion;
  ip.discretize = discretize;
  ip.threads = threads;
  ip.planar_cache = planarCache;
  ip.max_scan_cells = static_cast<std::uint64_t>(maxScanCells);
  ip.range_noise_std = rangeNoiseStd;
  ip.range_noise_std_per_meter = rangeNoiseStdPerMeter;
  ip.range_noise_cutoff = rangeNoiseCutoff;
  ip.range_noise_shared_band = static_cast<std::uint32_t>(rangeNoiseSharedBand);
  if (mrptGrid()) ip.graded_unit = 1.0 / 16.0;  // the int8 grids' unit (mrpt_grid::gradedStep)
  return ip;
}

void CRTreeOccupancyGridMap::TInsertionOptions::validate() const {
  const std::string sec = "insertOpts";
  if (sensorModelPreset != "mrpt_grid" && sensorModelPreset != "octomap")
    badOption(sec, "sensorModelPreset", "must be mrpt_grid or octomap, got '" + sensorModelPreset + "'");
  sensorModelFromString(sensorModel);  // throws with the accepted names
  if (!(std::isfinite(rangeNoiseStd) && rangeNoiseStd >= 0.0f))
    badOption(sec, "rangeNoiseStd", "must be a finite sigma >= 0 [m], got " + std::to_string(rangeNoiseStd));
  if (!(std::isfinite(rangeNoiseStdPerMeter) && rangeNoiseStdPerMeter >= 0.0f))
    badOption(sec, "rangeNoiseStdPerMeter", "must be finite and >= 0 [m per m], got " + std::to_string(rangeNoiseStdPerMeter));
  if (!(rangeNoiseCutoff >= 0.5f && rangeNoiseCutoff <= 10.0f))
    badOption(sec, "rangeNoiseCutoff", "must lie in [0.5, 10] sigma, got " + std::to_string(rangeNoiseCutoff));
  if (rangeNoiseSharedBand < 0)
    badOption(sec, "rangeNoiseSharedBand", "must be a count of beams >= 0, got " + std::to_string(rangeNoiseSharedBand));
  if (!(maxFreenessInvalidRanges == 0.0f ||
        (isProbability(maxFreenessInvalidRanges) && maxFreenessInvalidRanges > 0.5f)))
    badOption(sec, "maxFreenessInvalidRanges", "must be 0 or lie in (0.5, 1), got " +
                                                   std::to_string(maxFreenessInvalidRanges));
  if (!(std::isfinite(horizontalTolerance) && horizontalTolerance >= 0.0f))
    badOption(sec, "horizontalTolerance", "must be a non-negative angle");
  if (!std::isfinite(mapAltitude)) badOption(sec, "mapAltitude", "must be finite");
  if (sonarConeWeighting != "uniform" && sonarConeWeighting != "elfes")
    badOption(sec, "sonarConeWeighting", "must be uniform or elfes, got '" + sonarConeWeighting + "'");
  if (mrptGrid() && wideningBeamsWithDistance)
    badOption(sec, "wideningBeamsWithDistance",
              "COccupancyGridMap2D's widening beams are not reproduced by the mrpt_grid preset: set it to false");
  mergePolicyFromString(mergePolicy);
  if (!isProbability(maxOccupancyUpdateCertainty) || maxOccupancyUpdateCertainty <= 0.5f)
    badOption(sec, "maxOccupancyUpdateCertainty", "must lie in (0.5, 1), got " + std::to_string(maxOccupancyUpdateCertainty));
  if (!(maxFreenessUpdateCertainty == 0.0f ||
        (isProbability(maxFreenessUpdateCertainty) && maxFreenessUpdateCertainty > 0.5f)))
    badOption(sec, "maxFreenessUpdateCertainty", "must be 0 or lie in (0.5, 1), got " +
                                                     std::to_string(maxFreenessUpdateCertainty));
  // Checked in both presets (mrpt_grid does not use them): a bad value is an error wherever it stands.
  if (!isProbability(clampingMin) || !isProbability(clampingMax) || !(clampingMin < 0.5f && 0.5f < clampingMax))
    badOption(sec, "clampingMin/clampingMax", "need 0 < clampingMin < 0.5 < clampingMax < 1");
  if (!isProbability(occupiedThreshold)) badOption(sec, "occupiedThreshold", "must lie in (0, 1)");
  if (!std::isfinite(maxDistanceInsertion)) badOption(sec, "maxDistanceInsertion", "must be finite");
  if (mrptGrid() && !(maxDistanceInsertion > 0.0f))
    badOption(sec, "maxDistanceInsertion", "must be > 0 in the mrpt_grid preset (the grid cuts every beam there)");
  if (decimation < 1) badOption(sec, "decimation", "must be >= 1");
  if (decimation_3d_range < 1 || decimation_3d_range > 255) badOption(sec, "decimation_3d_range", "must be in [1, 255]");
  if (threads < 1 || threads > 256) badOption(sec, "threads", "must be in [1, 256]");
  if (!(maxScanCells >= 0.0 && maxScanCells <= 4e18 && maxScanCells == std::floor(maxScanCells)))
    badOption(sec, "maxScanCells", "must be a whole number of cells, 0 (no bound) to 4e18");
  const bool minSet = !std::isnan(rotatingScan_minElevation_deg), maxSet = !std::isnan(rotatingScan_maxElevation_deg);
  if (minSet != maxSet)
    badOption(sec, "rotatingScan_min/maxElevation_deg", "set both (explicit ring elevations) or neither");
  if (minSet && (!(rotatingScan_minElevation_deg <= rotatingScan_maxElevation_deg) ||
                 !(std::abs(rotatingScan_minElevation_deg) <= 90) || !(std::abs(rotatingScan_maxElevation_deg) <= 90)))
    badOption(sec, "rotatingScan_min/maxElevation_deg", "need -90 <= min <= max <= 90");
  toMapParams(0.1).validate();
}

MapParams CRTreeOccupancyGridMap::TInsertionOptions::toMapParams(double resolution) const {
  MapParams p;
  p.resolution = resolution;
  p.merge = mergePolicyFromString(mergePolicy);
  if (mrptGrid()) {
    p.log_odds = mrpt_grid::logOddsParams(mrpt_grid::stepsOf(*this), occupiedThreshold);
    return p;
  }
  p.log_odds.prob_hit = maxOccupancyUpdateCertainty;
  p.log_odds.prob_miss =
      1.0 - (maxFreenessUpdateCertainty == 0.0f ? maxOccupancyUpdateCertainty : maxFreenessUpdateCertainty);
  p.log_odds.clamp_min = clampingMin;
  p.log_odds.clamp_max = clampingMax;
  p.log_odds.occupied_threshold = occupiedThreshold;
  return p;
}

// ---- TLikelihoodOptions ------------------------------------------------------------------

void CRTreeOccupancyGridMap::TLikelihoodOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& s,
                                                                   const std::string& sec) {
  const std::string m = s.read_string(sec, "likelihoodMethod", "");
  // COccupancyGridMap2D's names and numbers (0 meant the likelihood field before: doc/mrpt_map.md).
  if (!m.empty() && !likelihoodMethodFromString(m, likelihoodMethod))
    badOption(sec, "likelihoodMethod", "unknown method '" + m + "' (expected one of COccupancyGridMap2D's: " +
                                           kLikelihoodMethodNames + ")");
  LF_stdHit = readFloat(s, sec, "LF_stdHit", LF_stdHit);
  LF_zHit = readFloat(s, sec, "LF_zHit", LF_zHit);
  LF_zRandom = readFloat(s, sec, "LF_zRandom", LF_zRandom);
  LF_maxRange = readFloat(s, sec, "LF_maxRange", LF_maxRange);
  const int lfd = readInt(s, sec, "LF_decimation", static_cast<int>(LF_decimation));
  if (lfd < 1) badOption(sec, "LF_decimation", "must be >= 1, got " + std::to_string(lfd));
  LF_decimation = static_cast<uint32_t>(lfd);
  LF_maxCorrsDistance = readFloat(s, sec, "LF_maxCorrsDistance", LF_maxCorrsDistance);
  LF_useSquareDist = readBool(s, sec, "LF_useSquareDist", LF_useSquareDist);
  enableLikelihoodCache = readBool(s, sec, "enableLikelihoodCache", enableLikelihoodCache);
  rayTracing_decimation = readInt(s, sec, "rayTracing_decimation", rayTracing_decimation);
  rayTracing_stdHit = readFloat(s, sec, "rayTracing_stdHit", rayTracing_stdHit);
  loadGridLikelihoodKeys(*this, s, sec);
  reportUnknownKeys(s, sec,
                    {"likelihoodMethod", "LF_stdHit", "LF_zHit", "LF_zRandom", "LF_maxRange", "LF_decimation",
                     "LF_maxCorrsDistance", "LF_useSquareDist", "LF_alternateAverageMethod", "enableLikelihoodCache",
                     "rayTracing_decimation", "rayTracing_stdHit", "rayTracing_useDistanceFilter", "MI_exponent",
                     "MI_skip_rays", "MI_ratio_max_distance", "consensus_takeEachRange", "consensus_pow",
                     "OWA_weights", "scanLikelihoodOnGridView"});
  validateInSection(sec, [this] { validate(); });
}

void CRTreeOccupancyGridMap::TLikelihoodOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c,
                                                                 const std::string& sec) const {
  c.write(sec, "likelihoodMethod", std::string(likelihoodMethodName(likelihoodMethod)));
  c.write(sec, "LF_stdHit", LF_stdHit);
  c.write(sec, "LF_zHit", LF_zHit);
  c.write(sec, "LF_zRandom", LF_zRandom);
  c.write(sec, "LF_maxRange", LF_maxRange);
  c.write(sec, "LF_decimation", static_cast<int>(LF_decimation));
  c.write(sec, "LF_maxCorrsDistance", LF_maxCorrsDistance);
  c.write(sec, "LF_useSquareDist", LF_useSquareDist);
  c.write(sec, "enableLikelihoodCache", enableLikelihoodCache);
  c.write(sec, "rayTracing_decimation", rayTracing_decimation);
  c.write(sec, "rayTracing_stdHit", rayTracing_stdHit);
  saveGridLikelihoodKeys(*this, c, sec);
}

void CRTreeOccupancyGridMap::TLikelihoodOptions::validate() const {
  const std::string sec = "likelihoodOpts";
  checkLikelihoodValues(*this, "rtog::CRTreeOccupancyGridMap", sec);
  if (!likelihoodMethodName(likelihoodMethod)) badOption(sec, "likelihoodMethod", "not a known method");
}

// ---- TMatchingOptions --------------------------------------------------------------------

void CRTreeOccupancyGridMap::TMatchingOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& s,
                                                                 const std::string& sec) {
  matching2D_minZ = readFloat(s, sec, "matching2D_minZ", matching2D_minZ);
  matching2D_maxZ = readFloat(s, sec, "matching2D_maxZ", matching2D_maxZ);
  validateInSection(sec, [this] { validate(); });
}

void CRTreeOccupancyGridMap::TMatchingOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c,
                                                               const std::string& sec) const {
  c.write(sec, "matching2D_minZ", matching2D_minZ);
  c.write(sec, "matching2D_maxZ", matching2D_maxZ);
}

void CRTreeOccupancyGridMap::TMatchingOptions::validate() const {
  if (!(std::isfinite(matching2D_minZ) && std::isfinite(matching2D_maxZ) && matching2D_minZ <= matching2D_maxZ))
    badOption("matchingOpts", "matching2D_minZ/matching2D_maxZ", "need finite minZ <= maxZ");
}

// ---- TMapDefinition ----------------------------------------------------------------------

CRTreeOccupancyGridMap::TMapDefinition::TMapDefinition() = default;

void CRTreeOccupancyGridMap::TMapDefinition::loadFromConfigFile_map_specific(
    const mrpt::config::CConfigFileBase& source, const std::string& sectionNamePrefix) {
  loadError.clear();
  try {
    const std::string sec = sectionNamePrefix + "_creationOpts";
    // A section pasted from a COccupancyGridMap3D config: that grid's keys with its defaults.
    grid3D = source.keyExists(sec, "min_z") || source.keyExists(sec, "max_z");
    if (grid3D) {
      resolution = 0.25;
      min_x = min_y = -5.0f, max_x = max_y = 5.0f;
      likelihoodOpts.LF_maxRange = 20.0f;
      likelihoodOpts.LF_decimation = 1;
    }
    resolution = readDouble(source, sec, "resolution", resolution);
    if (!(std::isfinite(resolution) && resolution >= 1e-4 && resolution <= 1e3))
      badOption(sec, "resolution", "must lie in [1e-4, 1e3] m, got " + std::to_string(resolution));
    readGridExtent(source, sec, min_x, max_x, min_y, max_y);
    if (grid3D) {
      min_z = readFloat(source, sec, "min_z", min_z);
      max_z = readFloat(source, sec, "max_z", max_z);
      if (!(std::isfinite(min_z) && std::isfinite(max_z) && min_z < max_z))
        badOption(sec, "min_z/max_z", "the 3D grid extent needs finite min_z < max_z");
      // The grid's own geometry (float resolution), checked now: a bad one is the section's error.
      mrpt_grid3d::makeFrame(min_x, max_x, min_y, max_y, min_z, max_z, static_cast<float>(resolution), resolution);
    }
    readGenericMapParams(source, sec, "rtog::CRTreeOccupancyGridMap", genericMapParams);
    reportUnknownKeys(source, sec,
                      {"resolution", "min_x", "max_x", "min_y", "max_y", "min_z", "max_z", "gridView_minZ", "gridView_maxZ",
                       "disableSaveAs3DObject", "enableSaveAs3DObject", "enableObservationLikelihood",
                       "enableObservationInsertion", "priorMap", "priorConfidence", "priorResolution", "priorOriginX",
                       "priorOriginY"});
    insertionOpts.loadFromConfigFile(source, sectionNamePrefix + "_insertOpts");
    likelihoodOpts.loadFromConfigFile(source, sectionNamePrefix + "_likelihoodOpts");
    if (grid3D) mrpt_grid3d::readSectionKeys(source, sectionNamePrefix, insertionOpts, likelihoodOpts);
    gridViewOpts.loadFromConfigFile(source, sec);
    priorOpts.loadFromConfigFile(source, sec);
    matchingOpts.loadFromConfigFile(source, sectionNamePrefix + "_matchingOpts");
  } catch (const std::exception& e) {
    loadError = e.what();
  }
}

void CRTreeOccupancyGridMap::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const {
  out << "resolution = " << resolution << "\n";
  insertionOpts.dumpToTextStream(out);
  likelihoodOpts.dumpToTextStream(out);
  gridViewOpts.dumpToTextStream(out);
  priorOpts.dumpToTextStream(out);
  matchingOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CRTreeOccupancyGridMap::internal_CreateFromMapDefinition(
    const mrpt::maps::TMetricMapInitializer& def) {
  const auto& d = dynamic_cast<const CRTreeOccupancyGridMap::TMapDefinition&>(def);
  if (!d.loadError.empty()) throw std::invalid_argument(d.loadError);
  auto m = std::make_unique<CRTreeOccupancyGridMap>(d.resolution, d.insertionOpts);
  m->setGridFrame(d.min_x, d.max_x, d.min_y, d.max_y);
  if (d.grid3D)
    m->setGridFrame3D(mrpt::math::TPoint3D(d.min_x, d.min_y, d.min_z), mrpt::math::TPoint3D(d.max_x, d.max_y, d.max_z),
                      static_cast<float>(d.resolution));
  m->likelihoodOptions = d.likelihoodOpts;
  m->gridViewOptions = d.gridViewOpts;
  m->matchingOptions = d.matchingOpts;
  m->genericMapParams = d.genericMapParams;
  // The prior's own geometry and resolution replace the definition's (as a loaded grid does);
  // its layer lies in the band of the view options.
  if (!d.priorOpts.priorMap.empty()) m->loadPrior(d.priorOpts);
  return m.release();
}

}  // namespace rtog
