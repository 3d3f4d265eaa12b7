// The rtog tool's commands, callable from tests; main.cpp only parses arguments.
#pragma once

#include <iosfwd>
#include <memory>
#include <optional>
#include <string>

#include "rtog/core/occupancy_map.hpp"

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
  std::string out_path;       ///< .rtog file to write; empty: do not save
  MapParams map;              ///< resolution, log-odds, merging (without --ini)
  InsertParams insert;        ///< sensor model, max range, threads (without --ini)
  int stride = 1;             ///< TUM: use every stride-th pixel in each direction (Default: 1)
  bool progress_bar = false;  ///< redraw one progress line (terminal) instead of printing lines
};

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
  std::string scene_path;        ///< MRPT .3Dscene (SceneViewer3D) of the occupied cuboids; empty: none
};

/// Writes the requested exports of a saved map. All outputs are written to `FILE.partial`
/// first and renamed only when every one succeeded, so a failure leaves no output behind.
/// Throws std::invalid_argument for bad options and std::runtime_error (naming the file) for
/// unreadable maps or failed writes. Returns the process exit code.
int exportMap(const ExportOptions& opts, std::ostream& out);

/// An output file written to `path + ".partial"` and renamed to `path` by commit(); if it is
/// destroyed before, the partial file is removed.
class PendingFile {
 public:
  /// Throws std::runtime_error if the temporary file cannot be created.
  explicit PendingFile(std::string path);
  ~PendingFile();
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;

  std::ostream& stream();
  const std::string& path() const { return path_; }
  /// Flushes and closes; throws std::runtime_error if any write failed.
  void close();
  /// close() (if not done), then renames into place; throws std::runtime_error on failure.
  void commit();

 private:
  std::string path_, tmp_;
  std::unique_ptr<std::ofstream> out_;
  bool committed_ = false;
};

/// Loads a .rtog map; throws std::runtime_error naming the file on failure.
OccupancyMap loadMap(const std::string& path);
/// Saves atomically (temporary file, then rename): nothing half-written on failure.
void saveMap(const OccupancyMap& map, const std::string& path);

}  // namespace rtog::cli
