// What `rtog build` and its tiled form share: the log read once, the map the options make, and
// the feeding of a map with every scan of the log (as many times as there are tiles).
#pragma once

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <memory>

#include <Eigen/Core>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/serialization/CSerializable.h>

#include "commands.hpp"
#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/rawlog_poses.h"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::cli {

/// The source of a build: TUM frames (their list; images are read as fed), an MRPT simplemap
/// (whole), or a rawlog (checked once, then read as a stream at every feeding: never whole).
struct BuildLog {
  image::DepthSequence seq;
  mrpt::maps::CSimpleMap simplemap;
  std::size_t rawlog_entries = 0;
};

/// Checks a rawlog (checkArchive): a truncated, corrupt or hostile one (or one with bytes after its
/// last entry) throws std::runtime_error with checkArchive's line, unless it is truncated and
/// `allow_truncated` (then a warning to `out`, and only the entries before the cut are read).
/// Returns the number of entries to read.
std::size_t checkRawlog(const std::string& path, bool allow_truncated, std::ostream& out);
/// Reads the first `entries` entries of a checked rawlog one at a time, as
/// CRawlog::loadFromRawLogFile takes them (a whole CRawlog gives its own entries; comments are
/// skipped), and visits each observation at its odometry pose (rtog::OdometryWalk): the log is
/// never held whole. Throws std::runtime_error naming an entry that is not an action, a sensory
/// frame or an observation.
void forEachRawlogObservation(const std::string& path, std::size_t entries, const OdometryVisit& visit);

/// The options' checks of every build (one source, --pose-uncertainty's conditions).
void checkBuildOptions(const BuildOptions& o);
/// Reads the source (checked first: a truncated or hostile file is an error, or with
/// --allow-truncated read up to the cut with a warning on `out`).
BuildLog readBuildLog(const BuildOptions& o, std::ostream& out);
/// The map the options make: the command line's (octomap preset) or the .ini's.
std::shared_ptr<CRTreeOccupancyGridMap> makeBuildMap(const BuildOptions& o);

struct FeedFigures {
  std::size_t scans = 0, points = 0, uncertain_frames = 0;
  double seconds = 0.0;  ///< inside the insertion calls
};
/// Inserts every scan of the log (within --scans) into `map`; a progress line on `progress` if given.
FeedFigures feedMap(const BuildOptions& o, const BuildLog& log, CRTreeOccupancyGridMap& map, std::ostream* progress);

/// The summary `rtog build` prints: beams, time, skips, the map's statistics.
void printBuildSummary(const BuildOptions& o, const CRTreeOccupancyGridMap& map, const FeedFigures& f, std::ostream& out);

/// `rtog build --tiles`: the map as tiles of space (doc/scale-out.md), built by this process or,
/// launched by mpirun, by its ranks.
int buildTiles(const BuildOptions& o, std::ostream& out);

/// Calls fn(origin, end points) for every `every`-th scan of the log (within --scans), the beams as
/// the map would insert them: what a first pass measures the work by.
void forEachBeams(const BuildOptions& o, const BuildLog& log, const CRTreeOccupancyGridMap& map, std::size_t every,
                  const std::function<void(const Eigen::Vector3d&, const std::vector<Eigen::Vector3f>&)>& fn);
/// The log's scans (TUM frames, simplemap frames) or entries (rawlog).
std::size_t logSize(const BuildLog& log);

}  // namespace rtog::cli
