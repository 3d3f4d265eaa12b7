// The insertion options of rtog::CRTreeOccupancyGridMap (CRTreeOccupancyGridMap::TInsertionOptions),
// in their own header as the map's class is large: every field with its default, the .ini key
// being the member's name (doc/mrpt_map.md).
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include <mrpt/config/CLoadableOptions.h>

#include "rtog/core/params.hpp"

namespace rtog {

/// Options for inserting observations into a CRTreeOccupancyGridMap ([<prefix>_insertOpts]),
/// which names them TInsertionOptions as MRPT's maps do. .ini key = member name.
struct RTreeInsertionOptions : public mrpt::config::CLoadableOptions {
  void loadFromConfigFile(const mrpt::config::CConfigFileBase& source, const std::string& section) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& target, const std::string& section) const override;
  /// Throws std::invalid_argument naming the first bad option.
  void validate() const;
  /// Sets maxOccupancyUpdateCertainty and maxFreenessUpdateCertainty from missRate and
  /// falseAlarmRate (both set); throws std::invalid_argument naming `section` otherwise.
  void applySensorChannel(const std::string& section = "insertOpts");

  /// Whose update rule the map follows (doc/mrpt_map.md): "mrpt_grid", COccupancyGridMap2D's
  /// (int8 log-odds, the occupied step three times the free one, a step per beam in beam order,
  /// the grid's raster for 2D scans: the grid's cells exactly), or "octomap", OctoMap's (float
  /// log-odds, one update per cell and scan, clamping at clampingMin/Max). (Default: mrpt_grid)
  std::string sensorModelPreset{"mrpt_grid"};
  /// "beam" (ray traced: free along the beam, occupied at its end), "endpoint", or
  /// "rangeNoise" (ray traced with Gaussian range noise, doc/range-noise.md; octomap preset
  /// only). (Default: beam)
  std::string sensorModel{"beam"};
  /// rangeNoise: sigma of a reading at range r is rangeNoiseStd + rangeNoiseStdPerMeter * r [m].
  /// (Default: 0.05)
  float rangeNoiseStd{0.05f};
  /// rangeNoise: growth of sigma with range [m per m]. (Default: 0)
  float rangeNoiseStdPerMeter{0.0f};
  /// rangeNoise: cells beyond r + rangeNoiseCutoff * sigma are left untouched [sigmas, 0.5 to
  /// 10]. (Default: 3)
  float rangeNoiseCutoff{3.0f};
  /// rangeNoise: beams of one scan ending in the same cell, if at least this many, share one
  /// band along the ray to the cell's centre (doc/range-noise.md); 0: a band each. (Default: 4)
  int rangeNoiseSharedBand{4};
  /// P(occupied) of a cell where a beam ends, as in COccupancyGridMap2D. (Default: 0.65)
  float maxOccupancyUpdateCertainty{0.65f};
  /// 1 - P(occupied) of a cell a beam crosses; 0 means "same as maxOccupancyUpdateCertainty",
  /// as in COccupancyGridMap2D. (Default: 0)
  float maxFreenessUpdateCertainty{0.0f};
  /// The sensor stated as a miss / false-alarm channel instead (rtog::SensorChannel):
  /// P(no detection | occupied). Set with falseAlarmRate, the pair replaces
  /// maxOccupancyUpdateCertainty and maxFreenessUpdateCertainty, which are read from it
  /// (prior 0.5); a section may state the sensor one way only. 0: not used. (Default: 0)
  float missRate{0.0f};
  /// P(detection | free), with missRate. 0: not used. (Default: 0)
  float falseAlarmRate{0.0f};
  /// mrpt_grid: P(free) of a cell crossed by a no-return beam; 0 means "same as
  /// maxOccupancyUpdateCertainty", as in COccupancyGridMap2D. (Default: 0)
  float maxFreenessInvalidRanges{0.0f};
  /// mrpt_grid: no-return beams clear space up to half the last valid range. (Default: true)
  bool considerInvalidRangesAsFreeSpace{true};
  /// mrpt_grid: 2D scans whose sensor is tilted more than this [rad; .ini in degrees] are
  /// not inserted, as in COccupancyGridMap2D. (Default: 0.05 deg)
  float horizontalTolerance{0.05f * 3.14159265358979f / 180.0f};
  /// mrpt_grid: insert only 2D scans taken within 1 mm of mapAltitude. (Default: false, 0)
  bool useMapAltitude{false};
  float mapAltitude{0.0f};
  /// mrpt_grid: COccupancyGridMap2D's widening beams; only false is supported. (Default: false)
  bool wideningBeamsWithDistance{false};
  /// octomap: lower clamping probability of a cell (mrpt_grid: the int8 range). (Default: 0.1192)
  float clampingMin{0.1192f};
  /// octomap: upper clamping probability of a cell. (Default: 0.971)
  float clampingMax{0.971f};
  /// Cells at or above this probability are occupied. (Default: 0.5)
  float occupiedThreshold{0.5f};
  /// Beams longer than this [m] clear space up to it and mark nothing occupied; <=0: no limit.
  /// (Default: 15)
  float maxDistanceInsertion{15.0f};
  /// Use one of every N beams of 2D scans, Velodyne/rotating scans and point clouds. (Default: 1)
  uint16_t decimation{1};
  /// Pixel decimation of depth images (CObservation3DRangeScan), as in COccupancyGridMap3D.
  /// (Default: 8)
  uint16_t decimation_3d_range{8};
  /// Leaf merging: "off", "clamped" (cells clamped to the same bound) or "equal". (Default: clamped)
  std::string mergePolicy{"clamped"};
  /// Trace each beam to the centre of its end cell and beams ending in one cell once. (Default: false)
  bool discretize{false};
  /// Threads tracing and applying beams (the result does not depend on it). (Default: the
  /// machine's hardware threads)
  int threads{rtog::defaultThreadCount()};
  /// 2D scans update dense per-brick layers in place and become leaves when the map is next
  /// read, not at every scan (the cells are the same either way). (Default: true)
  bool planarCache{true};
  /// A scan whose beams would touch bricks (cubes of 16^3 cells, 1 KiB each while traced) holding
  /// more cells than this is skipped whole and counted (InsertStats::skipped_over_budget): a
  /// bound on one scan's memory (InsertParams::max_scan_cells). 0: no bound. (Default: 1073741824,
  /// 2^30: 256 MiB)
  double maxScanCells{1073741824.0};
  /// Explicit ring elevations [deg] of a CObservationRotatingScan: if both are set, row r is at
  /// min + r*(max-min)/(rows-1). Unset (NaN), rings come from the lidar's calibration (MRPT's
  /// default table for VLP-16 / HDL-32E / HDL-64; MRPT 2.5's rotating scans carry none), and a
  /// multi-row scan of an unknown lidar is refused. (Default: NaN / NaN, unset)
  float rotatingScan_minElevation_deg{std::numeric_limits<float>::quiet_NaN()};
  float rotatingScan_maxElevation_deg{std::numeric_limits<float>::quiet_NaN()};
  /// "on": an observation inserted with a pose PDF (insertObservation with a
  /// CPose3DPDFGaussian / CPosePDFGaussian, loadFromSimpleMap, `rtog build --simplemap`) is
  /// blurred by the pose covariance (doc/pose-uncertainty.md); "off": inserted at the mean.
  /// octomap preset only. .ini: off | on. (Default: off)
  bool poseUncertainty{false};
  /// Sonar / IR readings (CObservationRange; doc/sonar.md): how the evidence of a reading is
  /// weighted across its cone: "uniform", every cell of the cone the whole step, as
  /// COccupancyGridMap2D; "elfes", scaled by 1 - (2 theta / aperture)^2 off the axis (octomap
  /// preset only). (Default: uniform)
  std::string sonarConeWeighting{"uniform"};

  /// The octomap preset stating a core map's rule and one insertion's settings (OctoMap's
  /// probabilities and clamping, the sensor model, range cut, merging, threads): what `rtog build`
  /// and the Python module make of their own options, so that both build the core call's map.
  static RTreeInsertionOptions fromCore(const MapParams& map, const InsertParams& ip);
  MapParams toMapParams(double resolution) const;
  /// The core's per-insertion settings these options give (sensor model, range cut, threads...).
  InsertParams toInsertParams() const;
  bool mrptGrid() const { return sensorModelPreset == "mrpt_grid"; }
};

}  // namespace rtog
