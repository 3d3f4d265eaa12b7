// Closed-loop exploration in a simulated world with known truth (doc/exploration.md): pick a view,
// plan a path to it on the map, drive it scanning, insert the scans, repeat; the coverage of the
// world's free space reachable from the start, against steps and against the path driven.
#pragma once

#include <cstdint>
#include <vector>

#include "rtog/core/explore.hpp"
#include "rtog/sim/sensors.hpp"
#include "rtog/sim/world.hpp"

namespace rtog::sim {

enum class ExploreStrategy {
  NearestFrontier,  ///< the reachable candidate of least path cost (Yamauchi's frontier explorer)
  InformationGain,  ///< the candidate of best utility, gain * exp(-lambda * cost) (nextBestViews)
};

struct ExplorationParams {
  double resolution = 0.1;     ///< the map's cells [m] (Default: 0.1)
  ScannerParams scanner;       ///< the robot's 2D scanner
  double scan_every = 1.0;     ///< a scan each this many metres along a path (Default: 1)
  int max_steps = 60;          ///< views driven to at most (Default: 60)
  double stop_coverage = 0.95; ///< stop once this share of the free space is known (Default: 0.95)
  ViewOptions views;           ///< candidates and scoring (the band and sensor are set from the scanner)
  std::uint32_t seed = 7;      ///< the scanner's noise

  /// The runs of doc/exploration.md: a 6 m scanner of 1 degree steps, a robot of 0.25 m radius,
  /// candidates 1 m from regions of 10 cells or more, 48 of them planned.
  static ExplorationParams indoor() {
    ExplorationParams p;
    p.scanner.max_range = 6.0;
    p.scanner.step_deg = 1.0;
    p.views.plan.radius = 0.25;
    p.views.standoff = 1.0;
    p.views.planned = 48;
    p.views.frontiers.min_region_cells = 10;
    return p;
  }
};

/// The state after each view driven to (step 0: the first scan at the start).
struct ExplorationStep {
  int step = 0;
  double path_length = 0.0;   ///< driven so far [m]
  double coverage = 0.0;      ///< known share of the reachable free cells at the scan height
  std::size_t scans = 0;
};

/// Explores `world` from its trajectory's first pose with `strategy` until the coverage reaches
/// stop_coverage, no candidate view is reachable, or max_steps. Each step takes the candidates of
/// nextBestViews with a path of at least half a metre and a positive gain; the robot drives the
/// path scanning, stops short of a cell the world occupies, knows its own body's cells free, and
/// plans a step without its radius when it finds itself within the radius of an obstacle.
std::vector<ExplorationStep> explore(const World& world, ExploreStrategy strategy, const ExplorationParams& params);

/// The path length [m] at which `steps` first reach `coverage` (interpolated within the step that
/// crosses it), or a negative number if they never do.
double lengthToCoverage(const std::vector<ExplorationStep>& steps, double coverage);

}  // namespace rtog::sim
