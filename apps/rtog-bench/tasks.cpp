// rtog-bench rows of what the map is for: risk-aware planning against MRPT's PlannerSimple2D, and
// a log built in chunks by separate processes and fused against one build.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <limits>
#include <ostream>
#include <stdexcept>

#include <unistd.h>

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/nav/planners/PlannerSimple2D.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/serialization/CArchive.h>

#include "bench.hpp"
#include "process.hpp"
#include "rtog/core/plan.hpp"
#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/rawlog_poses.h"

namespace rtog::bench {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct PlanningMap {
  std::string name;
  CRTreeOccupancyGridMap map{0.05};
  Eigen::Vector2d from, to;  ///< where the robot stood first and half-way
};

void loadSena(const std::string& rawlog, PlanningMap& m) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(rawlog) || rl.size() == 0) throw std::runtime_error("cannot read rawlog " + rawlog);
  std::vector<Eigen::Vector2d> robot;
  forEachOdometryObservation(rl, [&](const mrpt::obs::CObservation::Ptr& obs, const mrpt::poses::CPose3D& pose, std::size_t) {
    m.map.insertObservation(*obs, pose);
    robot.emplace_back(pose.x(), pose.y());
  });
  m.from = robot.front(), m.to = robot[robot.size() / 2];
}

void loadMalaga(const std::string& simplemap, PlanningMap& m) {
  mrpt::maps::CSimpleMap sm;
  mrpt::io::CFileGZInputStream f(simplemap);
  auto ar = mrpt::serialization::archiveFrom(f);
  ar >> sm;
  std::vector<Eigen::Vector2d> robot;
  for (const auto& pair : sm) {
    const mrpt::poses::CPose3D p = pair.pose->getMeanVal();
    for (const auto& obs : *pair.sf) m.map.insertObservation(*obs, p);
    robot.emplace_back(p.x(), p.y());
  }
  m.from = robot.front(), m.to = robot[robot.size() / 2];
}

/// The least distance from the points to an occupied cell's centre (all z), by brute force.
template <class Points>
double leastClearance(const OccupancyMap& map, const Points& points) {
  std::vector<Eigen::Vector2d> occupied;
  const double res = map.resolution();
  map.forEachLeaf([&](const Box& b, float v) {
    if (v < map.logOddsModel().occupiedThreshold()) return;
    for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
      for (std::int32_t x = b.min.x; x <= b.max.x; ++x) occupied.emplace_back((x + 0.5) * res, (y + 0.5) * res);
  });
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& p : points)
    for (const auto& c : occupied) best = std::min(best, (c - p).norm());
  return best;
}

Result planRow(const PlanningMap& m, const std::string& method) {
  Result r;
  r.dataset = m.name + " (planning)";
  r.method = method;
  r.resolution = m.map.resolution();
  r.extra["plan"] = 1;
  return r;
}

}  // namespace

void runPlanning(const std::string& mrpt_datasets_dir, const Options& opts, std::vector<Result>& out, std::ostream& log) {
  std::vector<PlanningMap> maps(2);
  maps[0].name = "SENA", maps[1].name = "Malaga CS building";
  loadSena(mrpt_datasets_dir + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog", maps[0]);
  loadMalaga(mrpt_datasets_dir + "/malaga-cs-fac-building.simplemap.gz", maps[1]);
  constexpr double kRadius = 0.3;
  const int repeats = std::max(1, opts.repeats);
  for (const PlanningMap& m : maps) {
    log << "planning on " << m.name << ": " << repeats << " plans a method\n";
    // MRPT's wavefront on the map's 2D view (obstacles grown by the radius).
    {
      mrpt::nav::PlannerSimple2D planner;
      planner.robotRadius = static_cast<float>(kRadius);
      planner.minStepInReturnedPath = 0.0f;
      const auto view = m.map.gridView();
      std::vector<double> ms;
      std::deque<mrpt::math::TPoint2D> path;
      for (int i = 0; i < repeats; ++i) {
        bool not_found = true;
        path.clear();
        const auto t0 = Clock::now();
        planner.computePath(*view, mrpt::poses::CPose2D(m.from.x(), m.from.y(), 0), mrpt::poses::CPose2D(m.to.x(), m.to.y(), 0),
                            path, not_found);
        ms.push_back(msSince(t0));
        if (not_found) throw std::runtime_error("PlannerSimple2D found no path on " + m.name);
      }
      Result r = planRow(m, "MRPT PlannerSimple2D (wavefront, radius 0.3 m)");
      std::vector<Eigen::Vector2d> pts;
      double length = 0;
      for (std::size_t i = 0; i < path.size(); ++i) {
        pts.emplace_back(path[i].x, path[i].y);
        if (i) length += (pts[i] - pts[i - 1]).norm();
      }
      r.extra["length_m"] = length, r.extra["clearance_m"] = leastClearance(m.map.map(), pts), r.extra["plan_ms"] = median(ms);
      out.push_back(r);
    }
    for (const double te : {0.0, 10.0})
      for (const bool whole : {true, false}) {
        PlanOptions o;
        o.te = te, o.ta = 1.0, o.radius = kRadius, o.cross_free_cuboids = whole;
        std::vector<double> ms, grid_ms;
        PlanResult p;
        PlanGrid g;
        for (int i = 0; i < repeats; ++i) {
          const auto t0 = Clock::now();
          g = buildPlanGrid(m.map.map(), m.from, m.to, o);
          grid_ms.push_back(msSince(t0));
          const auto t1 = Clock::now();
          p = planOnGrid(g, m.from, m.to, o);
          ms.push_back(msSince(t1));
        }
        if (!p.found) throw std::runtime_error("rtog found no path on " + m.name);
        char name[96];
        std::snprintf(name, sizeof name, "rtog plan, Te %g, %s", te, whole ? "free cuboids crossed whole" : "cell by cell");
        Result r = planRow(m, name);
        r.extra["length_m"] = p.length, r.extra["risk"] = p.risk, r.extra["clearance_m"] = leastClearance(m.map.map(), p.path);
        r.extra["plan_ms"] = median(ms), r.extra["grid_ms"] = median(grid_ms);
        r.extra["expanded"] = double(p.expanded), r.extra["nodes"] = double(g.risk.size()), r.extra["cuboids"] = double(g.rects.size());
        out.push_back(r);
      }
  }
}

std::vector<ChunkedLog> chunkedLogs(const std::string& tum_dir, const std::string& sena_rawlog) {
  std::vector<ChunkedLog> logs;
  const std::size_t frames = image::readTumSequence(tum_dir).frames.size();
  for (const double res : {0.05, 0.02})
    logs.push_back({"TUM fr2/pioneer_slam2 (" + std::to_string(frames) + " frames)",
                    {"--tum", tum_dir, "--resolution", res == 0.05 ? "0.05" : "0.02"}, frames / 2, res});
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(sena_rawlog) || rl.size() == 0) throw std::runtime_error("cannot read rawlog " + sena_rawlog);
  std::size_t scans = 0;  // as rtog build --scans counts them
  forEachOdometryObservation(rl, [&](const mrpt::obs::CObservation::Ptr&, const mrpt::poses::CPose3D&, std::size_t) { ++scans; });
  logs.push_back({"SENA 2D laser (" + std::to_string(scans) + " scans)", {"--rawlog", sena_rawlog, "--resolution", "0.05"},
                  scans / 2, 0.05});
  return logs;
}

void runChunkedBuilds(const std::string& rtog_cli, const std::vector<ChunkedLog>& logs, const Options& opts,
                      std::vector<Result>& out, std::ostream& log) {
  const auto dir = std::filesystem::temp_directory_path() / ("rtog_bench_chunks_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = [&](const char* n) { return (dir / n).string(); };
  const int repeats = std::max(1, opts.repeats);
  for (const ChunkedLog& l : logs) {
    log << "chunked build of " << l.name << ": " << repeats << " rounds\n";
    std::vector<double> one, two, fuse, total, first, second;
    for (int i = 0; i < repeats; ++i) {
      auto base = l.input;
      base.insert(base.begin(), rtog_cli);
      base.insert(base.begin() + 1, "build");
      const auto with = [&](std::vector<std::string> extra) {
        auto a = base;
        a.insert(a.end(), extra.begin(), extra.end());
        return a;
      };
      auto t0 = Clock::now();
      waitSucceeded(startProcess(with({"--out", file("whole.rtog")})), "rtog build (whole)");
      one.push_back(msSince(t0) / 1e3);
      // Each chunk alone (as on a machine of its own), then both at once on this one.
      t0 = Clock::now();
      waitSucceeded(startProcess(with({"--scans", "0:" + std::to_string(l.split), "--out", file("a.rtog")})), "rtog build (first chunk)");
      first.push_back(msSince(t0) / 1e3);
      t0 = Clock::now();
      waitSucceeded(startProcess(with({"--scans", std::to_string(l.split) + ":", "--out", file("b.rtog")})), "rtog build (second chunk)");
      second.push_back(msSince(t0) / 1e3);
      t0 = Clock::now();
      const pid_t a = startProcess(with({"--scans", "0:" + std::to_string(l.split), "--out", file("a.rtog")}));
      const pid_t b = startProcess(with({"--scans", std::to_string(l.split) + ":", "--out", file("b.rtog")}));
      waitSucceeded(a, "rtog build (first chunk)");
      waitSucceeded(b, "rtog build (second chunk)");
      two.push_back(msSince(t0) / 1e3);
      const auto t1 = Clock::now();
      waitSucceeded(startProcess({rtog_cli, "fuse", file("a.rtog"), file("b.rtog"), "--out", file("c.rtog")}), "rtog fuse");
      fuse.push_back(msSince(t1) / 1e3);
      total.push_back(msSince(t0) / 1e3);
    }
    Result r;
    r.dataset = l.name + " (chunked build)";
    r.method = "rtog build: one process vs 2 chunk processes at once + rtog fuse";
    r.resolution = l.resolution;
    r.extra["chunks"] = 1;
    r.extra["one_process_s"] = median(one), r.extra["two_chunks_s"] = median(two), r.extra["fuse_s"] = median(fuse);
    r.extra["chunked_total_s"] = median(total);
    r.extra["first_chunk_s"] = median(first), r.extra["second_chunk_s"] = median(second);
    r.file_bytes = std::filesystem::file_size(file("c.rtog"));
    out.push_back(r);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace rtog::bench
