// The rtog tool's commands, callable from tests; main.cpp only parses arguments.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "rtog/core/explore.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/plan.hpp"

namespace rtog::cli {

struct BuildOptions {
  // Exactly one source:
  std::string tum_dir;        ///< directory with groundtruth_poses.txt and depth/
  std::string rawlog_path;    ///< MRPT rawlog (poses from odometry, if any)
  std::string simplemap_path; ///< MRPT simplemap (poses from the map)
  /// MRPT map definition: the first `rtreeOccupancyGrid` map of the CMultiMetricMap defined in
  /// `ini_section` gives resolution and options; the command-line map options are then unused.
  std::string ini_path;
  std::string ini_section = "MappingApplication";  ///< (Default: MappingApplication)
  std::string out_path;       ///< .rtog file to write (never one of the inputs); empty: do not save
  MapParams map;              ///< resolution, log-odds, merging (without --ini)
  InsertParams insert;        ///< sensor model, max range, threads (without --ini)
  int stride = 1;             ///< TUM: use every stride-th pixel in each direction (Default: 1)
  /// --simplemap: blur each frame by its pose covariance (poseUncertainty = on; without --ini).
  /// (Default: false)
  bool pose_uncertainty = false;
  /// Sonar / IR readings of a rawlog or simplemap (CObservationRange): weighting across the cone,
  /// uniform | elfes (sonarConeWeighting; without --ini). (Default: elfes)
  std::string sonar_cone_weighting = "elfes";
  bool progress_bar = false;  ///< redraw one progress line (terminal) instead of printing lines
  /// Only scans scans_from <= i < scans_to of the log (TUM frames, simplemap frames, rawlog
  /// observations, counted from 0): chunks of one log built apart and joined by `rtog fuse`.
  /// (Default: all)
  std::size_t scans_from = 0, scans_to = static_cast<std::size_t>(-1);
  /// --rawlog: a log whose file ends inside an entry is read up to it, with a warning that
  /// counts what was dropped, instead of refused. (Default: false)
  bool allow_truncated = false;
  /// Build the map as tiles of space, each a region of whole bricks holding exactly the single
  /// build's cells there, into the directory --out: a count, or "auto" (four a rank under mpirun,
  /// else four). Empty: one map file. (Default: empty)
  std::string tiles;
};

/// "A:B" (either may be empty: from the start, to the end) as [A, B); throws
/// std::invalid_argument unless A < B.
std::pair<std::size_t, std::size_t> parseScanRange(const std::string& text);

/// Builds a map from real logs, prints progress and a summary (scans, points, time, leaves,
/// memory) to `out`, and saves it. Throws std::invalid_argument / std::runtime_error with a
/// clear message on bad options or unreadable inputs. Returns the process exit code.
int build(const BuildOptions& opts, std::ostream& out);

/// Prints a saved map's statistics (plain or JSON). Returns the process exit code.
int info(const std::string& map_path, bool json, std::ostream& out);

void printStatistics(const OccupancyMap& map, std::ostream& out);

struct ExportOptions {
  std::string map_path;          ///< .rtog map to read
  std::string ply_path;          ///< occupied cuboids as a triangle mesh; empty: none
  bool ply_ascii = false;        ///< ASCII PLY instead of binary little-endian (Default: false)
  std::string bt_path;           ///< OctoMap binary tree (.bt); empty: none
  std::string png_path;          ///< horizontal slice image; empty: none (needs slice_z)
  std::optional<double> slice_z; ///< height of the slice [m]
  /// The PNG shows each cell's probability (grey, unknown light blue) instead of its class.
  /// (Default: false)
  bool png_probability = false;
  /// The PNG is one pixel a cell with nothing around it (data for scripts), not the picture
  /// (cells scaled up, axes in metres, scale bar, legend). (Default: false)
  bool png_cells = false;
  std::string scene_path;        ///< MRPT .3Dscene (SceneViewer3D) of the occupied cuboids; empty: none
};

/// Writes the requested exports of a saved map, all or none (see output_files.hpp): no output
/// may be the input map or another output, and a failure replaces none of them. Throws
/// std::invalid_argument for bad options and std::runtime_error (naming the file) for
/// unreadable maps or failed writes. Returns the process exit code.
int exportMap(const ExportOptions& opts, std::ostream& out);

struct FuseOptions {
  std::string map_a;  ///< the map fused into (its lattice, clamping and merging are the result's)
  std::string map_b;  ///< the map whose evidence is added
  /// The second map's frame in the first's: x y z [m], yaw pitch roll [deg] (MRPT's CPose3D
  /// order). (Default: 0 0 0 0 0 0)
  std::array<double, 6> pose{};
  std::string out_path;  ///< the fused map (.rtog; never one of the inputs)
  int threads = defaultThreadCount();
  /// Estimate map_b's pose by registration (ICP on occupied cells, rtog::registerMaps; `pose`, if
  /// given, is its guess: x, y, yaw) and fuse with its covariance blurred in. (Default: false)
  bool register_maps = false;
  /// --register: the height band [m] of the occupied cells matched. (Default: all)
  std::array<double, 2> register_band{-1000.0, 1000.0};
};

/// The pose x y z [m] yaw pitch roll [deg] as MRPT's CPose3D has it; throws
/// std::invalid_argument for a value that is not finite.
Eigen::Isometry3d poseFromXyzYpr(const std::array<double, 6>& p);

/// Fuses map_b into map_a (OccupancyMap::fuse) and saves the result, all or nothing. Throws
/// std::invalid_argument for bad options (the same file twice, a bad pose, no --out) and
/// std::runtime_error naming the file for unreadable maps or failed writes. Returns the exit code.
int fuse(const FuseOptions& opts, std::ostream& out);

struct PriorOptions {
  std::string image_path;    ///< a blueprint image (PNG, JPEG, ...): white free, black occupied, mid-grey unknown
  std::string gridmap_path;  ///< or an MRPT .gridmap / .gridmap.gz (its own geometry)
  double resolution = 0.05;  ///< image only: metres per pixel (Default: 0.05)
  std::array<double, 2> origin{};  ///< image only: map coordinates of its lower-left corner [m] (Default: 0 0)
  double confidence = 0.7;   ///< TPriorMapOptions::priorConfidence, in (0.5, 1] (Default: 0.7)
  std::string out_path;      ///< the map (.rtog; never the input)
};

/// Makes a map of a prior (CRTreeOccupancyGridMap::loadPrior) and saves it, all or nothing.
/// Throws std::invalid_argument for bad options, std::runtime_error naming the file for an
/// unreadable input or a failed write. Returns the exit code.
int prior(const PriorOptions& opts, std::ostream& out);

struct PlanCommandOptions {
  std::string map_path;     ///< the map (.rtog)
  Eigen::Vector3d from{0, 0, 0}, to{0, 0, 0};  ///< start and goal [m]
  bool three_d = false;     ///< plan through the cells in 3D (from/to given with Z), not a band's columns
  PlanOptions plan;         ///< Te, Ta, unknown cells' risk, radius, band, cuboids crossed whole
  std::string out_path;     ///< the path as text: "x y" per line (never the input)
  std::string png_path;     ///< the planning grid with the path; empty: none
};

/// Plans a risk-aware path on a saved map (rtog::planPath2D, or planPath3D) and writes it, all or nothing.
/// Throws std::invalid_argument for bad options or a blocked start/goal, std::runtime_error if no
/// path exists or a file cannot be read or written. Returns the exit code.
int plan(const PlanCommandOptions& opts, std::ostream& out);

struct ImageOptions {
  std::string map_path;                 ///< the map (.rtog)
  double zmin = -1000.0, zmax = 1000.0; ///< the band [m] (--slice-z Z: Z Z)
  double threshold = 0.5;               ///< occupied at P >= this (Default: 0.5)
  double blur_sigma = 0.0;              ///< Gaussian blur [m] before the threshold; 0: none
  int open_k = 0, close_k = 0;          ///< morphological opening / closing of the occupied mask; 0: none
  bool hough = false;                   ///< wall segments (Hough) into the JSON and the picture
  double hough_min_length = 1.0, hough_max_gap = 0.3;  ///< [m]
  bool segment = false;                 ///< connected free regions
  std::string out_path;                 ///< JSON: geometry, segments [[x0, y0, x1, y1], ...], regions
  std::string png_path;                 ///< the band with segments and regions drawn; empty: none
  std::string prior_png_path;           ///< the (blurred) band as a prior image; empty: none
};

/// Image operations on a map's band (rtog/image/grid_ops.hpp), written all or nothing. Throws
/// std::invalid_argument for bad options, std::runtime_error for unreadable maps or failed writes.
int imageOps(const ImageOptions& opts, std::ostream& out);

struct ExploreCommandOptions {
  std::string map_path;        ///< the map (.rtog)
  Eigen::Vector3d from{0, 0, 0};  ///< the robot [m]
  bool three_d = false;        ///< 3D frontiers and views (from given with Z), not a band's
  ViewOptions views;           ///< sensor, frontiers (band), standoff, candidates, lambda, plan
  std::string out_path;        ///< JSON: frontier regions and ranked views
  std::string png_path;        ///< the band with the frontiers and the best views drawn; empty: none
};

/// Frontiers and next-best views of a saved map (rtog/core/explore.hpp), written all or nothing.
/// Throws std::invalid_argument for bad options, std::runtime_error for unreadable maps or failed writes.
int explore(const ExploreCommandOptions& opts, std::ostream& out);

/// What `e` says in one line a person reads (rtog::errorLine, rtog/mrpt/error_line.h).
std::string oneLine(const std::exception& e);

/// Loads a map file (the core format or the MRPT map's gzip archive), from a file or a pipe;
/// throws std::runtime_error naming the file on failure, including bytes after the map.
OccupancyMap loadMap(const std::string& path);

/// `n` bytes gzip-compressed into `out`, in memory (rtog::gzip::compress). (MRPT's
/// compress_gz_data_block goes through a file in /tmp named by the clock: two processes in the
/// same microsecond share it.)
void writeGzip(const void* data, std::size_t n, std::ostream& out);
/// What a child process found reading an MRPT archive file (a rawlog, a simplemap) entry by
/// entry (rawlog_input.cpp).
struct ArchiveCheck {
  std::uint64_t bytes = 0;    ///< of the log as read (a gzip file decompressed)
  std::size_t entries = 0;    ///< read whole; with a problem, the index of the entry that failed
  std::uint64_t offset = 0;   ///< where that entry starts (bytes at the end: the whole log read)
  bool truncated = false;     ///< the file ends inside that entry
  std::string problem;        ///< empty if every entry was read; else one line naming the entry
};
/// Reads every entry of the file (`what`: "rawlog" or "simplemap", for messages) in a child
/// process, each under an address-space bound of twice the bytes left in the file (plus 64 MiB):
/// a length field that the file cannot hold fails there, not in this process.
ArchiveCheck checkArchive(const std::string& path, const char* what);
/// Checks a simplemap file by checkArchive before MRPT's loader reads it: a truncated, corrupt or
/// hostile one, or one of other than one object, throws std::runtime_error with one line.
void checkSimplemap(const std::string& path);
/// Saves through an OutputSet: the old file stays intact unless the new one was written whole.
void saveMap(const OccupancyMap& map, const std::string& path);

}  // namespace rtog::cli
