// rtog-bench: rtog against OctoMap and MRPT's grids, side by side in one process, on the
// same scans, resolution and sensor parameters.
#pragma once

#include <functional>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mrpt::maps {
class CMetricMap;
}
namespace rtog {
class OccupancyMap;
}
namespace rtog::app {
class OutputSet;
}

namespace rtog::bench {

/// One scan in the map frame.
struct Scan {
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> points;
};

struct Dataset {
  std::string name;
  std::vector<Scan> scans;
  bool planar = false;  ///< 2D laser data (also compared with COccupancyGridMap2D)
  std::size_t points() const;
};

/// What one method measured on one dataset at one resolution.
struct Result {
  std::string dataset, method;
  double resolution = 0;
  double insert_seconds = 0;      ///< median over the repeats
  std::vector<double> build_seconds;  ///< every timed build, in the order built
  double points_per_second = 0;
  std::size_t structure_bytes = 0;
  double rss_growth_bytes = 0;    ///< resident set growth while building one map
  std::size_t leaves = 0;
  double point_query_ns = 0;
  std::size_t file_bytes = 0;
  double octomap_agreement = -1;  ///< class agreement with plain OctoMap, -1: not computed
  std::map<std::string, double> extra;
};

/// Builds of one method at most, over all rounds.
constexpr int kMaxBuilds = 60;

struct Options {
  int repeats = 5;                          ///< rounds of builds, every method in each (Default: 5)
  double min_seconds = 1.0;                 ///< a fast method's builds timed over all rounds (Default: 1.0)
  std::vector<double> resolutions{0.05, 0.1};
  std::size_t query_count = 200000;         ///< random point queries per map (Default: 200000)
  double max_range = -1;                    ///< beams cut here (<= 0: none) (Default: -1)
  std::vector<std::string> methods;         ///< run only methods whose name contains one of these (Default: all)
  std::string raster_dir;                   ///< each dataset's first rtog map as a raster here (Default: "", none)
};

/// True if `opts.methods` names part of `method` (or names nothing: every method runs).
bool selected(const Options& opts, const std::string& method);
/// The middle value (of an even count the upper one); 0 for none.
double median(std::vector<double> v);

/// The 2D frontier of a built map (frontier_rows.cpp): extra["frontier_ms"] (median of 9) and
/// extra["frontier_cells"], from rtog's cuboids or by a dense scan of a COccupancyGridMap2D; other
/// maps are left out.
void measureFrontiers(const mrpt::maps::CMetricMap& map, Result& r);

/// `s` with every character but letters and digits made '_', for file names.
std::string slug(std::string s);

/// Writes the map as one signed byte per cell over its key bounds, x fastest, then y, then z:
/// 0 unknown, else the log-odds in steps of 0.05 (clamped to +-127, a known 0 as 1). A
/// compression yardstick for the map's information content. Returns the cell count.
std::size_t writeLogOddsRaster(const OccupancyMap& map, const std::string& path);

Dataset loadTum(const std::string& dir);
/// 3D scans of an MRPT rawlog (Velodyne, rotating scans, point clouds), robot at the origin.
Dataset loadRawlog3D(const std::string& path, const std::string& name);

/// A 2D laser log: MRPT's SENA rawlog (odometry poses), rtog against COccupancyGridMap2D,
/// both through CMetricMap::insertObservation and computeObservationLikelihood (LF Thrun,
/// the same decimation, 5). Appends to `out`.
void run2D(const std::string& rawlog, const Options& opts, std::vector<Result>& out, std::ostream& log);

/// Risk-aware planning on SENA's and Malaga's maps (the MRPT map at 0.05 m) side by side with
/// MRPT's PlannerSimple2D on the map's 2D view, radius 0.3 m, from where the robot stood first to
/// where it stood half-way: path length, least clearance, planning time, and rtog's nodes
/// expanded crossing free cuboids whole and cell by cell. Appends to `out`.
void runPlanning(const std::string& mrpt_datasets_dir, const Options& opts, std::vector<Result>& out, std::ostream& log);

/// A log for the chunked-build row: `rtog build` arguments that read it, and where to split it.
struct ChunkedLog {
  std::string name;
  std::vector<std::string> input;  ///< e.g. {"--tum", DIR, "--resolution", "0.05"}
  std::size_t split = 0;           ///< the chunks are --scans 0:split and split:
  double resolution = 0;
};
/// The logs of the chunked-build row: the TUM frames and SENA's rawlog, each split in halves.
std::vector<ChunkedLog> chunkedLogs(const std::string& tum_dir, const std::string& sena_rawlog);
/// Wall times (medians of opts.repeats rounds) of one `rtog build` process over the whole log
/// against two `rtog build --scans` processes at once and `rtog fuse` of their maps.
void runChunkedBuilds(const std::string& rtog_cli, const std::vector<ChunkedLog>& logs, const Options& opts,
                      std::vector<Result>& out, std::ostream& log);

/// Runs every method on `data`; appends to `out`. Progress lines go to `log`.
void runDataset(const Dataset& data, const Options& opts, std::vector<Result>& out, std::ostream& log);

/// What a report states about the run besides the results: machine, versions, date, rounds.
struct RunInfo {
  std::map<std::string, std::string> machine;
  int repeats = Options{}.repeats;
  double min_seconds = Options{}.min_seconds;
};
/// This machine (CPU model, cores, memory, kernel; the compiler, OctoMap and MRPT versions the
/// bench was built with) and the time, from the system itself.
std::map<std::string, std::string> machineFacts();
/// This machine, now, with the rounds of `opts`.
RunInfo currentRun(const Options& opts);

/// JSON of the results and the run.
void writeJson(const std::vector<Result>& results, const RunInfo& run, std::ostream& out);
/// Reads writeJson's file back (for a report re-rendered without measuring again). A file from
/// before the rounds were recorded gets the default rounds. Throws std::runtime_error naming
/// what is missing or malformed.
std::vector<Result> readJson(const std::string& path, RunInfo& run);
/// The planning and chunked-build sections of the report (their rows only).
void writeTaskSections(const std::vector<Result>& results, std::ostream& md);
/// Whether a row belongs to those sections (not to the insertion tables).
bool isTaskRow(const Result& r);

/// The rows of the MRPT apps as processes, from app_rows.py's JSON (dataset "MRPT apps: <log>",
/// method "<app> | <map>"); throws std::runtime_error for a file that is not such a list.
std::vector<Result> readAppRows(const std::string& file);
/// Their section of the report, if any.
void writeAppRows(const std::vector<Result>& results, std::ostream& md);

/// The Markdown report with target ratios and PASS/FAIL; its bar charts are added to `files`
/// as PNGs in `img_dir` (the report links them as img/NAME.png).
void writeMarkdown(const std::vector<Result>& results, const RunInfo& run, std::ostream& md,
                   const std::string& img_dir, app::OutputSet& files);

/// A run of the bench as its command line gives it.
struct Command {
  Options opts;
  std::string tum_dir;            ///< TUM depth sequence
  std::string mrpt_datasets_dir;  ///< Debian mrpt-common's datasets
  std::vector<std::string> only;  ///< datasets: tum, vlp16, rotscan, sena, plan, chunks (none: all)
  std::string json, markdown, img_dir = ".";
  std::string from_json;          ///< render the report from this JSON, measure nothing
  std::string first_scan_helper;  ///< the rtog-first-scan executable
  std::string rtog_cli;           ///< the rtog executable (chunked builds)
  /// Rows of datasets not measured in this run are taken from this JSON (a partial run merged
  /// into a full report). (Default: none)
  std::string merge_json;
  /// app_rows.py --json files: their rows join the results (replacing rows of the same app, log
  /// and map), in the JSON and the report. (Default: none)
  std::vector<std::string> app_rows;
};
/// Measures (or reads --from-json), then writes the report's files all or none. Progress goes
/// to `out`. Returns the exit code.
int runCommand(const Command& cmd, std::ostream& out, std::ostream& err);

}  // namespace rtog::bench
