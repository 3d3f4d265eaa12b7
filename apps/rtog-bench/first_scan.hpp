// The first scan as MRPT users meet it: a map made from a CMultiMetricMap .ini section (as
// MRPT's applications make theirs), one observation inserted through
// CMetricMap::insertObservation, in a process of its own (nothing warmed up: no pages, no
// caches, no lazy initialization of an earlier map). Measured: the insertion's time, and the
// heap the process holds after the insertion returned, beside the map's own count of its bytes.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "bench.hpp"

namespace mrpt::obs {
class CObservation3DRangeScan;
}
namespace rtog::image {
struct DepthFrame;
struct DepthIntrinsics;
}

namespace rtog::bench {

/// A dataset whose first scan goes into the fresh maps.
struct FirstScanSource {
  /// "tum": the first depth frame of a TUM directory, as a CObservation3DRangeScan at its camera
  /// pose; "rawlog3d": a rawlog's first observation, robot at the origin (as the bench's 3D
  /// sets); "rawlog2d": a rawlog's first 2D laser scan at its odometry pose.
  std::string kind;
  std::string path;
  std::string label;  ///< the dataset's name in the report
};

/// A map type a source's first scan goes into, and in which form.
struct FirstScanMap {
  std::string type;          ///< the CMultiMetricMap .ini name: rtreeOccupancyGrid, octoMap, occupancyGrid
  bool as_recorded = false;  ///< the observation as recorded, not in the form every map type takes
};
/// rtreeOccupancyGrid and octoMap on the observation in the form both take, occupancyGrid
/// (COccupancyGridMap2D) too for a 2D scan, and rtreeOccupancyGrid on the observation as
/// recorded where that form differs (a depth image without points, a Velodyne scan's packets).
std::vector<FirstScanMap> firstScanMaps(const FirstScanSource& source);

/// A TUM depth frame as an MRPT user has it: a CObservation3DRangeScan (the depth image, the
/// camera's intrinsics) whose sensor pose is the frame's camera pose, for a robot at the origin.
std::shared_ptr<mrpt::obs::CObservation3DRangeScan> tumDepthObservation(const image::DepthFrame& frame,
                                                                        const image::DepthIntrinsics& intrinsics);

/// What one fresh process measured.
struct FirstScanSample {
  std::string observation;    ///< the class inserted, e.g. "CObservationPointCloud"
  double create_seconds = 0;  ///< CMultiMetricMap::setListOfMaps
  double insert_seconds = 0;  ///< insertObservation
  /// Heap in use after insertObservation returned less before it (malloc's in-use bytes,
  /// mallinfo2 uordblks, plus its mmap'ed chunks, hblkhd: glibc serves big blocks by mmap).
  double heap_held_bytes = 0;
  double heap_held_uordblks = 0;  ///< the uordblks part alone
  std::size_t map_bytes = 0;  ///< the map's own count: memoryBytes(), memoryUsage(), its cells
  std::size_t points = 0;     ///< the observation's points (or beams), counted after the measurement
};

/// The helper process (rtog-first-scan): `--kind K --path P --map TYPE --resolution R
/// [--as-recorded]`. Prints
/// the sample as one JSON object on `out`. Returns the exit code (2: bad command line or an
/// observation the map cannot insert, 1: a failure).
int firstScanMain(int argc, char** argv, std::ostream& out, std::ostream& err);

/// One sample: runs `helper` as a new process and reads its output. Throws std::runtime_error
/// if it cannot start, fails, or prints no sample.
FirstScanSample runFirstScanProcess(const std::string& helper, const FirstScanSource& source, const FirstScanMap& map,
                                    double resolution);

/// For every source, resolution of `opts` and map (those `opts.methods` selects), one Result
/// with the medians of `opts.repeats` fresh processes (the maps taking turns, so that they
/// sample the same spells of the machine). The method names the map type and the observation
/// class; the rows carry extra["first_scan"] = 1 and extra["as_recorded"] (0 or 1).
void runFirstScans(const std::string& helper, const std::vector<FirstScanSource>& sources, const Options& opts,
                   std::vector<Result>& out, std::ostream& log);

/// The report's rows: the targets (first scan >= 20x faster than COctoMap's, heap held
/// <= 1.5x memoryBytes()) for its target table, and a section of the figures.
void writeFirstScanTargets(const std::vector<Result>& results, std::ostream& md);
void writeFirstScanSection(const std::vector<Result>& results, std::ostream& md);

}  // namespace rtog::bench
