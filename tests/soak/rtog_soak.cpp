// Soak: real 2D scans replayed lap after lap into one CRTreeOccupancyGridMap, as a robot that
// drives the same building for hours, inserting each scan and then scoring it against the map
// as a SLAM or localization loop does (which covers the planar cache every scan). Each lap is
// the log's odometry path moved by a small random rigid offset (fixed seed): the area explored
// stops growing after the first laps while the cells keep being revisited from other poses.
//
// At every checkpoint: invariants of the R-tree, leaves, structure bytes, heap in use, RSS and
// the scans per second of the last stretch. Exits 1 if an invariant breaks or, with
// --max-growth, if the structure or the heap grew by more than that fraction from the
// checkpoint after the first lap to the last. Throughput is printed, never asserted.
#include <malloc.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CRawlog.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/rawlog_poses.h"

namespace {

struct Checkpoint {
  std::size_t scans = 0, leaves = 0, structure = 0, heap = 0, rss = 0;
  double scans_per_second = 0;
};

std::size_t rssBytes() {
  std::ifstream f("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

std::size_t heapBytes() { return mallinfo2().uordblks; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rtog soak: real scans replayed lap after lap into one map"};
  std::string rawlog = "/usr/share/mrpt/datasets/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog";
  std::size_t scans = 10000, every = 1000;
  double resolution = 0.05, max_growth = -1, lap_sigma_xy = 0.05, lap_sigma_deg = 1.0;
  app.add_option("--rawlog", rawlog, "2D laser rawlog (actions + sensory frames)")->check(CLI::ExistingFile);
  app.add_option("--scans", scans, "scans to insert in all")->check(CLI::PositiveNumber);
  app.add_option("--every", every, "scans between checkpoints")->check(CLI::PositiveNumber);
  app.add_option("--resolution", resolution, "cell size [m]")->check(CLI::PositiveNumber);
  app.add_option("--lap-sigma-xy", lap_sigma_xy, "std. dev. of each lap's offset [m]")->check(CLI::NonNegativeNumber);
  app.add_option("--lap-sigma-deg", lap_sigma_deg, "std. dev. of each lap's rotation [deg]")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-growth", max_growth,
                 "fail if structure or heap grow by more than this fraction after the first lap");
  CLI11_PARSE(app, argc, argv);

  mrpt::obs::CRawlog log;
  if (!log.loadFromRawLogFile(rawlog)) {
    std::cerr << "rtog_soak: cannot read " << rawlog << "\n";
    return 2;
  }
  std::vector<std::pair<mrpt::poses::CPose3D, mrpt::obs::CObservation2DRangeScan::Ptr>> lap;
  rtog::forEachOdometryObservation(log, [&](const mrpt::obs::CObservation::Ptr& o, const mrpt::poses::CPose3D& p,
                                            std::size_t) {
    if (auto s = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(o)) lap.emplace_back(p, s);
  });
  if (lap.empty()) {
    std::cerr << "rtog_soak: no 2D scans in " << rawlog << "\n";
    return 2;
  }
  rtog::CRTreeOccupancyGridMap map(resolution);
  std::mt19937 rng(20261201);
  std::normal_distribution<double> dxy(0.0, lap_sigma_xy), dyaw(0.0, lap_sigma_deg * M_PI / 180.0);
  mrpt::poses::CPose3D offset;
  std::vector<Checkpoint> points;
  std::printf("%8s %9s %12s %12s %12s %10s %s\n", "scans", "leaves", "structure_B", "heap_B", "rss_B", "scans/s",
              "invariants");
  auto t0 = std::chrono::steady_clock::now();
  double sink = 0;
  bool ok = true;
  for (std::size_t i = 0; i < scans; ++i) {
    if (i % lap.size() == 0) offset = mrpt::poses::CPose3D(dxy(rng), dxy(rng), 0.0, dyaw(rng), 0.0, 0.0);
    const auto& [pose, scan] = lap[i % lap.size()];
    const mrpt::poses::CPose3D p = offset + pose;
    map.insertObservation(*scan, p);
    sink += map.computeObservationLikelihood(*scan, p);
    if ((i + 1) % every == 0 || i + 1 == scans) {
      const auto t1 = std::chrono::steady_clock::now();
      Checkpoint c;
      c.scans = i + 1;
      c.leaves = map.map().leafCount();
      c.structure = map.map().memoryBytes();
      c.heap = heapBytes();
      c.rss = rssBytes();
      const std::size_t done = c.scans - (points.empty() ? 0 : points.back().scans);
      c.scans_per_second = double(done) / std::chrono::duration<double>(t1 - t0).count();
      const std::string inv = map.map().checkInvariants();
      ok = ok && inv.empty();
      std::printf("%8zu %9zu %12zu %12zu %12zu %10.1f %s\n", c.scans, c.leaves, c.structure, c.heap, c.rss,
                  c.scans_per_second, inv.empty() ? "ok" : inv.c_str());
      std::fflush(stdout);
      points.push_back(c);
      t0 = std::chrono::steady_clock::now();
    }
  }
  // From the first checkpoint a full lap after the start, when the explored area is known.
  std::size_t base = 0;
  while (base + 1 < points.size() && points[base].scans < lap.size()) ++base;
  const Checkpoint &b = points[base], &e = points.back();
  const double g_structure = double(e.structure) / double(b.structure) - 1.0;
  const double g_heap = double(e.heap) / double(b.heap) - 1.0;
  const double throughput = e.scans_per_second / points.front().scans_per_second;
  std::printf("lap %zu scans; from scan %zu to %zu: structure %+.2f %%, heap %+.2f %%; last/first throughput %.3f; "
              "likelihood sum %.6g\n",
              lap.size(), b.scans, e.scans, 100 * g_structure, 100 * g_heap, throughput, sink);
  if (!ok) {
    std::cerr << "rtog_soak: an invariant broke\n";
    return 1;
  }
  if (max_growth >= 0 && (g_structure > max_growth || g_heap > max_growth)) {
    std::cerr << "rtog_soak: memory grew by more than " << 100 * max_growth << " % after the first lap\n";
    return 1;
  }
  return 0;
}
