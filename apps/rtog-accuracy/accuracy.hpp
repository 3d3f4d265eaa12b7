// Accuracy against ground truth: rtog, OctoMap and MRPT's dense grids built from the same
// simulated scans of a seeded synthetic world, scored cell by cell against the exact truth.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "rtog/sim/calibration.hpp"
#include "rtog/sim/metrics.hpp"
#include "rtog/sim/sensors.hpp"
#include "rtog/sim/world.hpp"

namespace rtog::accuracy {

struct Config {
  std::uint32_t seed = 42;            ///< world seed
  std::uint32_t lidar_seed = 1001;    ///< LiDAR noise seed
  std::uint32_t scanner_seed = 2002;  ///< 2D scanner noise seed
  double resolution = 0.1;            ///< [m], every map
  int stride = 1;                     ///< use every stride-th trajectory pose
  sim::WorldParams world;
  /// A VLP-16-like LiDAR: 16 rings over +-15 deg, 0.2 deg azimuth steps.
  sim::LidarParams lidar = [] {
    sim::LidarParams p;
    p.azimuth_steps = 1800;
    return p;
  }();
  sim::ScannerParams scanner;
  /// Pose noise of the "_pose_noise" scenarios: every scan is placed in the maps at its true pose
  /// plus an error, dx, dy ~ N(0, pose_sigma_xy^2), dyaw ~ N(0, pose_sigma_yaw_deg^2), each a
  /// Gauss-Markov sequence along the trajectory; the blurred rtog maps are told this covariance.
  /// Both sigmas 0: no such scenarios.
  double pose_sigma_xy = 0.05;        ///< [m]
  double pose_sigma_yaw_deg = 1.0;    ///< [deg]
  double pose_correlation = 0.9;      ///< of consecutive poses' errors (sim::samplePoseErrors)
  std::uint32_t pose_seed = 3003;     ///< pose error seed
  /// The world the "_calibrated" maps' sensor rates are measured in (sim::measureInverseModel,
  /// exact poses); equal to `seed`: no calibrated maps (they would be calibrated on the test).
  std::uint32_t calibration_seed = 4004;
  /// The "_calibrated" maps clamp at the log-odds of this many agreeing readings. One reading's
  /// clamp leaves each cell at its last reading (a measured step reaches it), which ties cells
  /// of different histories and costs ranking (AUC); see doc/accuracy.md.
  int calibrated_clamp_readings = 2;
};

/// One map in one scenario.
struct MapResult {
  std::string scenario;  ///< "lidar3d", "scanner2d", and with pose noise "..._pose_noise"
  /// "rtog" (beam model), "rtog_endpoint", "rtog_range_noise", each with "_pose_blur" in the pose
  /// noise scenarios; "octomap", "mrpt_grid3d", "mrpt_grid2d"
  std::string map;
  double insert_seconds = 0;
  std::size_t observed_cells = 0;  ///< cells of the evaluation region the map knows
  std::size_t observed_outside = 0;  ///< known cells outside the region (not scored)
  double agreement_octomap = 0;      ///< share of evaluated cells with OctoMap's class (incl. unknown)
  sim::ClassMetrics metrics;
};

struct Scenario {
  std::string name;
  bool planar = false;     ///< the 2D scanner's scenario (scored in the scan plane's layer)
  bool pose_noise = false; ///< scans placed at noisy poses
  std::string description;
  std::size_t scans = 0, beams = 0, returns = 0;
  std::size_t region_cells = 0;     ///< cells of the key box the truth was rasterized on
  std::size_t evaluated_cells = 0;  ///< cells observed by at least one map
  std::size_t truth_occupied = 0, truth_free = 0;  ///< among evaluated cells
};

struct Report {
  Config config;
  std::string world_summary;
  std::string octomap_version, mrpt_version;
  std::vector<Scenario> scenarios;
  std::vector<MapResult> results;
  sim::InverseModelRates calibration_lidar, calibration_scanner;  ///< measured rates
  double total_seconds = 0;
};

/// Builds everything and scores it; progress lines go to `log`.
Report run(const Config& cfg, std::ostream& log);

void writeJson(const Report& r, std::ostream& os);
void writeMarkdown(const Report& r, std::ostream& os);
/// ROC curves as a PNG image, one panel per scenario, one coloured curve per map, with a legend
/// (OpenCV). Throws std::runtime_error if the image cannot be encoded.
void writeRocPng(const Report& r, std::ostream& os);
/// Reliability diagrams (occupied share against mean P per bin of P, with the diagonal of
/// perfect calibration), one panel per scenario, as a PNG image (OpenCV).
void writeReliabilityPng(const Report& r, std::ostream& os);

/// The command line: `rtog-accuracy [--seed N] [--resolution M] [--stride K | --quick]
/// [--sigma M] [--pose-sigma-xy M] [--pose-sigma-yaw DEG] [--json FILE] [--markdown FILE]
/// [--png FILE] [--reliability-png FILE]`; the files are written all or
/// none (rtog/app/output_files.hpp). Returns the exit code: 0, 1 (run or files failed), 2 (bad
/// command line).
int main(int argc, char** argv, std::ostream& out, std::ostream& err);

}  // namespace rtog::accuracy
