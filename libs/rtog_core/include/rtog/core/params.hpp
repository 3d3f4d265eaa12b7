// Parameters of a map and of one insertion.
#pragma once

#include <cmath>

#include <cstdint>
#include <string>

#include "rtog/core/log_odds.hpp"
#include "rtog/core/rtree.hpp"

namespace rtog {

/// Inverse sensor model used to turn a beam into cell updates.
enum class SensorModel {
  BeamBased,     ///< ray traced: free along the beam, occupied at its end
  BeamEndPoint,  ///< end points only
  /// ray traced with Gaussian range noise: each cell takes P(occ | r) by total probability over
  /// where the surface lies given the reading (doc/range-noise.md); sigma -> 0 gives BeamBased
  RangeNoise,
};

/// When adjacent leaves are merged into one cuboid.
enum class MergePolicy {
  Off,      ///< every leaf stays one cell
  Clamped,  ///< cells whose log-odds converged to the same clamping bound (seed §2.5.2)
  Equal,    ///< any cells with bit-identical log-odds (lossless as well; more merging)
};

const char* toString(SensorModel m);
const char* toString(MergePolicy m);
SensorModel sensorModelFromString(const std::string& s);  ///< throws std::invalid_argument
MergePolicy mergePolicyFromString(const std::string& s);  ///< throws std::invalid_argument

struct MapParams {
  double resolution = 0.05;              ///< Cell edge length [m]. (Default: 0.05)
  LogOddsParams log_odds;                ///< Sensor and clamping probabilities. (Default: OctoMap's)
  MergePolicy merge = MergePolicy::Clamped;  ///< Leaf merging. (Default: Clamped)
  RTreeParams rtree;                     ///< Node capacities of the index. (Default: 16/6)

  void validate() const;
};

/// The machine's hardware threads (at least 1): the default thread count of an insertion.
int defaultThreadCount();

/// How a pose-blurred scan's poses are evaluated (InsertParams::blur_method).
enum class BlurMethod : std::uint8_t { Auto, Trace, Move };

/// Per-call insertion settings.
struct InsertParams {
  SensorModel model = SensorModel::BeamBased;  ///< (Default: BeamBased)
  /// Beams longer than this are cut here: free up to the cut, nothing occupied. <= 0 means
  /// unlimited. (Default: -1)
  double max_range = -1.0;
  /// Beams longer than this many cells (after the max_range cut) are skipped and counted in
  /// InsertStats::skipped_too_long: a bound on the cost of one beam, so that garbage ranges
  /// (a 100 km reading) cannot make one scan take minutes and millions of leaves. 65,536 cells
  /// are 3.3 km at 5 cm, 655 m at 1 cm. 0: no bound (the caller's call). (Default: 65536)
  std::uint32_t max_ray_cells = std::uint32_t{1} << 16;
  /// A bound on the memory one scan takes while it is traced: a scan whose beams touch bricks
  /// (the aligned cubes of 16^3 = 4,096 cells the update batch allocates, 1 KiB each) holding
  /// more cells than this is skipped whole, its beams counted in InsertStats::skipped_over_budget,
  /// the map unchanged. 2^30 cells are 262,144 bricks, 256 MiB: a 2D scan of 361 beams reaching
  /// 3 km touches 1.85 million; a depth image or a VLP-16 sweep within 100 m, a few thousand to
  /// tens of thousands. Planar scans (one z-layer) are bounded by their batch's own size (2^26
  /// cells) and reach it only if it is set lower; a pose-blurred scan (insertBlurred) is skipped
  /// if any of its poses' traces goes over; RangeNoise scans are not counted. 0: no bound.
  /// (Default: 2^30)
  std::uint64_t max_scan_cells = std::uint64_t{1} << 30;
  /// Trace each beam to the centre of its end cell and beams ending in the same cell once
  /// (OctoMap's `discretize`): much faster for dense clouds. (Default: false)
  bool discretize = false;
  /// Threads tracing and applying beams; the map is bit-identical for any count, so the default
  /// is the machine's hardware threads. (Default: defaultThreadCount())
  int threads = defaultThreadCount();
  /// Scans whose origin and end cells all lie in one z-layer (2D range scans) update the log-odds
  /// of their bricks' layers in place and are covered with leaves when the map is next read,
  /// instead of reshaping leaves at every scan. The cells are the same either way. (Default: true)
  bool planar_cache = true;
  /// RangeNoise: the range noise sigma = range_noise_std + range_noise_std_per_meter * r [m] of a
  /// reading r. 0 and 0 give the beam model's cells and values. (Default: 0.05)
  double range_noise_std = 0.05;
  /// RangeNoise: growth of sigma with range [m per m]. (Default: 0)
  double range_noise_std_per_meter = 0.0;
  /// RangeNoise: the surface is taken to lie within this many sigma of the reading; cells beyond
  /// r + cutoff * sigma are left untouched. (Default: 3)
  double range_noise_cutoff = 3.0;
  /// RangeNoise: the beams of one scan that end in the same cell, if at least this many do,
  /// share one band, graded along the ray to that cell's centre at the centre's range; each
  /// still frees the cells before its own band. A Kinect frame puts some 20 beams into a cell
  /// at 5 cm, whose bands are nearly the same cells: one band, not 20. Fewer beams, and sparse
  /// scans, keep a band each. 0: every beam its own band. (Default: 4)
  std::uint32_t range_noise_shared_band = 4;
  /// The graded changes (range noise, pose blur) rounded to whole multiples of this log-odds
  /// unit, half away from zero, so that a map of integer log-odds stays on its lattice (MRPT's
  /// int8 grids: 1/16, as the mrpt_grid preset sets it). 0: not rounded. (Default: 0)
  double graded_unit = 0.0;
  /// A pose-blurred scan given as moves of the scan at the mean pose (OccupancyMap::insertBlurred
  /// with PoseMove): how each pose's change of the cells is found. Trace: the scan moved and
  /// traced from each pose. Move: traced once, at the mean, and the trace moved to each pose (the
  /// same up to the raster; a lookup per cell and pose instead of a walk per beam and pose).
  /// Auto: Move where the beams surely cross the cells they touch many times over (their cell
  /// steps are 8 times the cells of the scan's bounding box or more: a depth image's), Trace
  /// otherwise (LiDAR rings, 2D scans). (Default: Auto)
  BlurMethod blur_method = BlurMethod::Auto;

  /// A graded change as it enters the map (graded_unit).
  float graded(double delta) const { return gradedChange(delta, graded_unit); }
  static float gradedChange(double delta, double unit) {
    return static_cast<float>(unit > 0.0 ? std::round(delta / unit) * unit : delta);
  }

  /// Throws std::invalid_argument naming the field unless the values are usable.
  void validate() const;
};

}  // namespace rtog
