// `rtog build`: real logs (TUM depth frames, MRPT rawlogs and simplemaps) into a map.
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <sstream>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <string>

#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>

#include "build_log.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/ini_checks.h"
#include "rtog/mrpt/map_file.h"
#include "rtog/mrpt/rawlog_poses.h"

namespace rtog::cli {
namespace {

/// One redrawn line on a terminal, a plain line per 10 % otherwise; each when the percentage
/// moves; nothing without a stream. The leaf count is asked for only then: reading a map covers
/// its planar cache, which a 2D scan a time would otherwise pay at every scan (and a tile's
/// build, whose progress nobody reads, would pay at every per cent under mpirun's terminal).
class Progress {
 public:
  Progress(std::ostream* out, std::size_t total, bool bar, std::string unit = "scans")
      : out_(out), total_(total), bar_(bar), unit_(std::move(unit)) {}
  template <class Leaves>
  void update(std::size_t done, Leaves&& leaves) {
    if (!out_ || done == done_) return;
    done_ = done;
    const int pct = total_ ? int(std::min<std::size_t>(100, 100 * done / total_)) : 100;
    if (bar_ && (pct != last_ || done == total_)) {
      const int filled = pct * 30 / 100;
      *out_ << "\r[" << std::string(std::size_t(filled), '#') << std::string(std::size_t(30 - filled), ' ') << "] "
           << std::setw(3) << pct << "% " << done << "/" << total_ << " " << unit_ << ", " << leaves() << " leaves"
           << std::flush;
      if (done == total_) *out_ << "\n";
    } else if (!bar_ && (pct / 10 != last_ / 10 || done == total_)) {
      *out_ << "progress " << pct << "% (" << done << "/" << total_ << " " << unit_ << ", " << leaves() << " leaves)\n";
    }
    last_ = pct;
  }

 private:
  std::ostream* out_;
  std::size_t total_;
  bool bar_;
  std::string unit_;
  std::size_t done_ = std::size_t(-1);
  int last_ = -1;
};

/// Runs an MRPT loader with its diagnostics (printed to std::cerr) captured; throws with a
/// one-line message if it fails or reads nothing.
template <class Load>
void loadQuietly(const std::string& what, const std::string& path, Load&& load) {
  std::ostringstream captured;
  std::streambuf* old = std::cerr.rdbuf(captured.rdbuf());
  bool ok = false;
  try {
    ok = load();
  } catch (...) {
    ok = false;
  }
  std::cerr.rdbuf(old);
  if (!ok) throw std::runtime_error("cannot read " + what + " '" + path + "' (not a valid " + what + " file?)");
}

}  // namespace

std::shared_ptr<CRTreeOccupancyGridMap> makeBuildMap(const BuildOptions& o) {
  if (o.ini_path.empty()) {
    // The command-line options, in the map's MRPT terms.
    CRTreeOccupancyGridMap::TInsertionOptions io = CRTreeOccupancyGridMap::TInsertionOptions::fromCore(o.map, o.insert);
    io.poseUncertainty = o.pose_uncertainty;
    io.sonarConeWeighting = o.sonar_cone_weighting;
    io.validate();
    return std::make_shared<CRTreeOccupancyGridMap>(o.map.resolution, io);
  }
  return mapFromIni(o.ini_path, o.ini_section);
}

void checkBuildOptions(const BuildOptions& o) {
  const int sources = !o.tum_dir.empty() + !o.rawlog_path.empty() + !o.simplemap_path.empty();
  if (sources != 1) throw std::invalid_argument("give exactly one of --tum, --rawlog, --simplemap");
  if (o.pose_uncertainty && o.simplemap_path.empty())
    throw std::invalid_argument("--pose-uncertainty needs --simplemap (the only source with pose covariances)");
  if (o.pose_uncertainty && !o.ini_path.empty())
    throw std::invalid_argument("--pose-uncertainty is for the command-line options; with --ini set poseUncertainty = on in its _insertOpts");
}

BuildLog readBuildLog(const BuildOptions& o, std::ostream& out) {
  BuildLog log;
  if (!o.tum_dir.empty()) log.seq = image::readTumSequence(o.tum_dir);
  if (!o.simplemap_path.empty()) {
    // Checked first, as rawlogs are: MRPT's loader sizes buffers from the counts the file states.
    checkSimplemap(o.simplemap_path);
    loadQuietly("simplemap", o.simplemap_path,
                [&] { return log.simplemap.loadFromFile(o.simplemap_path) && !log.simplemap.empty(); });
  }
  // Entry by entry, checked first: a truncated, corrupt or hostile log is an error (or, truncated
  // and --allow-truncated, read up to the cut with a warning), never a shorter log.
  if (!o.rawlog_path.empty()) log.rawlog_entries = checkRawlog(o.rawlog_path, o.allow_truncated, out);
  return log;
}

FeedFigures feedMap(const BuildOptions& o, const BuildLog& log, CRTreeOccupancyGridMap& map, std::ostream* progress_out) {
  FeedFigures f;
  const auto timed = [&](auto&& insert) {
    const auto t0 = std::chrono::steady_clock::now();
    insert();
    f.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const auto inRange = [&](std::size_t i) { return i >= o.scans_from && i < o.scans_to; };
  const auto leaves = [&map] { return map.map().leafCount(); };
  if (!o.tum_dir.empty()) {
    Progress progress(progress_out, log.seq.frames.size(), o.progress_bar);
    const InsertParams ip = map.insertionOptions.toInsertParams();
    for (std::size_t i = 0; i < log.seq.frames.size(); ++i) {
      if (!inRange(i)) continue;
      const image::WorldScan scan = image::loadDepthScan(log.seq.frames[i], log.seq.intrinsics, o.stride);
      timed([&] { map.lastInsertStats = map.map().insertPointCloud(scan.origin, scan.points, ip); });
      // The core map is fed directly here: the figures the summary prints are kept by hand.
      map.totalInsertStats += map.lastInsertStats;
      map.invalidRangesSkipped += scan.pixels_without_depth;
      map.notifyMapChanged();
      ++f.scans;
      f.points += scan.points.size();
      progress.update(i + 1, leaves);
    }
  } else if (!o.simplemap_path.empty()) {
    Progress progress(progress_out, log.simplemap.size(), o.progress_bar);
    for (std::size_t i = 0; i < log.simplemap.size(); ++i) {
      if (!inRange(i)) continue;
      const auto [pose, sf] = log.simplemap.get(i);
      // The frame's pose PDF as a Gaussian: with poseUncertainty on, its covariance blurs the
      // frame; else it is inserted at the mean.
      mrpt::poses::CPose3DPDFGaussian robot;
      robot.copyFrom(*pose);
      f.uncertain_frames += robot.cov.trace() > 0.0;
      for (const auto& obs : *sf) {
        const std::size_t before = map.totalInsertStats.raysTotal();
        timed([&] { map.insertObservation(*obs, robot); });
        f.points += map.totalInsertStats.raysTotal() - before;
      }
      ++f.scans;
      progress.update(i + 1, leaves);
    }
  } else {
    Progress progress(progress_out, log.rawlog_entries, o.progress_bar, "rawlog entries");
    std::size_t index = 0;  // of the observation, for --scans
    forEachRawlogObservation(o.rawlog_path, log.rawlog_entries, [&](const mrpt::obs::CObservation::Ptr& obs,
                                                                     const mrpt::poses::CPose3D& robot, std::size_t entry) {
      if (!inRange(index++)) return;
      const std::size_t before = map.totalInsertStats.raysTotal();
      bool used = false;
      timed([&] { used = map.insertObservation(*obs, robot); });
      f.points += map.totalInsertStats.raysTotal() - before;
      f.scans += used;
      progress.update(entry + 1, leaves);
    });
    progress.update(log.rawlog_entries, leaves);
  }
  return f;
}

std::size_t logSize(const BuildLog& log) {
  return log.seq.frames.size() + log.simplemap.size() + log.rawlog_entries;
}

void forEachBeams(const BuildOptions& o, const BuildLog& log, const CRTreeOccupancyGridMap& map, std::size_t every,
                  const std::function<void(const Eigen::Vector3d&, const std::vector<Eigen::Vector3f>&)>& fn) {
  const auto inRange = [&](std::size_t i) { return i >= o.scans_from && i < o.scans_to && i % every == 0; };
  ObservationBeams beams;
  if (!o.tum_dir.empty()) {
    for (std::size_t i = 0; i < log.seq.frames.size(); ++i)
      if (inRange(i)) {
        const image::WorldScan scan = image::loadDepthScan(log.seq.frames[i], log.seq.intrinsics, o.stride);
        fn(scan.origin, scan.points);
      }
  } else if (!o.simplemap_path.empty()) {
    for (std::size_t i = 0; i < log.simplemap.size(); ++i) {
      if (!inRange(i)) continue;
      const auto [pose, sf] = log.simplemap.get(i);
      mrpt::poses::CPose3DPDFGaussian robot;
      robot.copyFrom(*pose);
      for (const auto& obs : *sf)
        if (map.extractBeams(*obs, robot.mean, beams, true)) fn(beams.origin, beams.points);
    }
  } else {
    std::size_t index = 0;
    forEachRawlogObservation(o.rawlog_path, log.rawlog_entries, [&](const mrpt::obs::CObservation::Ptr& obs,
                                                                     const mrpt::poses::CPose3D& robot, std::size_t) {
      if (inRange(index++) && map.extractBeams(*obs, robot, beams, true)) fn(beams.origin, beams.points);
    });
  }
}

int build(const BuildOptions& o, std::ostream& out) {
  checkBuildOptions(o);
  if (!o.tiles.empty()) return buildTiles(o, out);
  auto map = makeBuildMap(o);
  // The output is checked and opened before the work: an unwritable path, or one that names an
  // input (which the save would destroy), fails now and not after the last scan.
  std::vector<app::InputFile> inputs;
  if (!o.tum_dir.empty()) {
    const image::DepthSequence seq = image::readTumSequence(o.tum_dir);
    inputs.push_back({"--tum", o.tum_dir + "/groundtruth_poses.txt"});
    for (const auto& f : seq.frames) inputs.push_back({"--tum", f.depth_path});
  }
  if (!o.rawlog_path.empty()) inputs.push_back({"--rawlog", o.rawlog_path});
  if (!o.simplemap_path.empty()) inputs.push_back({"--simplemap", o.simplemap_path});
  if (!o.ini_path.empty()) inputs.push_back({"--ini", o.ini_path});
  app::OutputSet files(std::move(inputs));
  std::ostream* saved = o.out_path.empty() ? nullptr : &files.add("--out", o.out_path);
  const BuildLog log = readBuildLog(o, out);
  const FeedFigures f = feedMap(o, log, *map, &out);
  printBuildSummary(o, *map, f, out);
  if (saved) {
    map->map().write(*saved);
    files.commit();
    out << "saved             " << o.out_path << "\n";
  }
  return 0;
}

void printBuildSummary(const BuildOptions& o, const CRTreeOccupancyGridMap& map, const FeedFigures& f, std::ostream& out) {
  if (!o.simplemap_path.empty())
    out << "pose covariance:  " << f.uncertain_frames << " of " << f.scans << " frames have one ("
        << (map.insertionOptions.poseUncertainty ? "blurred in: poseUncertainty on" : "not used: poseUncertainty off")
        << ")\n";
  const InsertStats& st = map.totalInsertStats;
  out << "inserted " << f.points << " beams from " << f.scans << " scans in " << std::fixed << std::setprecision(3)
      << f.seconds << " s (" << std::setprecision(2) << (f.seconds > 0 ? f.points / f.seconds / 1e6 : 0.0)
      << " M beams/s), sensor model " << map.insertionOptions.sensorModel << "\n";
  out.unsetf(std::ios::floatfield);
  out << "skipped: " << st.skipped_non_finite << " non-finite, " << st.skipped_zero_length << " zero-length, "
      << st.skipped_out_of_range << " out of range, " << map.invalidRangesSkipped << " invalid ranges, "
      << st.skipped_too_long << " too long (over " << InsertParams{}.max_ray_cells << " cells), "
      << st.skipped_over_budget << " in scans over the cell budget (" << map.insertionOptions.toInsertParams().max_scan_cells
      << " cells); " << st.rays_truncated << " cut at the range limit or without a return\n";
  printStatistics(map.map(), out);
}

}  // namespace rtog::cli
