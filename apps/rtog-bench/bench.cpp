#include "bench.hpp"

#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <memory>
#include <random>
#include <thread>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>
#include <octomap/OcTree.h>

#include "methods.hpp"
#include "octomap_compare.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "rtog/image/tum_dataset.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/rawlog_poses.h"

namespace rtog::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Builds go in opts.repeats rounds, every method once or more in each: within a round a fast
// method builds again until min_seconds / repeats of its builds have been timed (at most
// kMaxBuilds in all), the fast methods taking turns build by build. So every method's
// builds sample the same spells of the machine (on a shared 2-vCPU VM one build in four may run
// at half speed, for seconds at a time), two fast methods' builds lie a few milliseconds apart,
// and the ratios of the medians hold. build(k) builds method k once and returns its seconds;
// only methods with include(k) take part.
template <class Include, class Build>
void buildInRounds(const Options& opts, std::vector<std::vector<double>>& times, Include&& include, Build&& build) {
  const double per_round = opts.min_seconds / opts.repeats;
  const auto most_per_round = static_cast<std::size_t>(std::max(1, kMaxBuilds / opts.repeats));
  for (int round = 0; round < opts.repeats; ++round) {
    std::vector<double> spent(times.size(), 0.0);
    std::vector<std::size_t> built(times.size(), 0);
    for (bool any = true; any;) {
      any = false;
      for (std::size_t k = 0; k < times.size(); ++k) {
        if (!include(k) || (built[k] > 0 && (spent[k] >= per_round || built[k] >= most_per_round))) continue;
        times[k].push_back(build(k));
        spent[k] += times[k].back();
        ++built[k];
        any = true;
      }
    }
  }
}

/// CPU seconds the hypervisor ran something else while this guest had work (the "steal" of
/// /proc/stat), summed over the CPUs; 0 where the kernel does not count it.
double stolenCpuSeconds() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  double user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0, steal = 0;
  in >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal;
  static const double ticks_per_second = double(sysconf(_SC_CLK_TCK));
  return in && cpu == "cpu" ? steal / ticks_per_second : 0.0;
}

/// Minor page faults of this process so far: first touches of memory the heap got from the kernel.
double minorFaults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_minflt);
}

double residentBytes() {
  std::ifstream in("/proc/self/statm");
  double pages = 0, resident = 0;
  in >> pages >> resident;
  return resident * 4096.0;
}

/// A copy of a built map, as a particle filter makes one when it resamples (MRPT's clone()): the
/// time of one (median of 9 rounds of 32 copies made and dropped, after the likelihood filled the
/// caches) and the heap 16 copies held at once take, per copy.
void measureCopies(const mrpt::maps::CMetricMap& map, Result& r) {
  constexpr int kRound = 32, kHeld = 16;
  std::vector<double> rounds;
  for (int round = 0; round < 9; ++round) {
    const auto t0 = Clock::now();
    for (int i = 0; i < kRound; ++i) std::unique_ptr<mrpt::rtti::CObject> copy(map.clone());
    rounds.push_back(seconds(t0, Clock::now()) / kRound);
  }
  r.extra["copy_us"] = median(rounds) * 1e6;
  malloc_trim(0);
  const auto before = mallinfo2().uordblks;
  {
    std::vector<std::unique_ptr<mrpt::rtti::CObject>> held;
    for (int i = 0; i < kHeld; ++i) held.emplace_back(map.clone());
    r.extra["copy_heap_bytes"] = double(mallinfo2().uordblks - before) / kHeld;
  }
}

}  // namespace

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

bool selected(const Options& o, const std::string& method) {
  return o.methods.empty() || std::any_of(o.methods.begin(), o.methods.end(), [&](const std::string& s) {
           return method.find(s) != std::string::npos;
         });
}

std::size_t Dataset::points() const {
  std::size_t n = 0;
  for (const auto& s : scans) n += s.points.size();
  return n;
}

Dataset loadTum(const std::string& dir) {
  Dataset d;
  d.name = "TUM fr2/pioneer_slam2 (10 Kinect frames)";
  const image::DepthSequence seq = image::readTumSequence(dir);
  for (const auto& f : seq.frames) {
    image::WorldScan w = image::loadDepthScan(f, seq.intrinsics, 1);
    d.scans.push_back(Scan{w.origin, std::move(w.points)});
  }
  return d;
}

Dataset loadRawlog3D(const std::string& path, const std::string& name) {
  mrpt::obs::CRawlog log;
  if (!log.loadFromRawLogFile(path)) throw std::runtime_error("cannot read rawlog " + path);
  Dataset d;
  d.name = name;
  const CRTreeOccupancyGridMap rotating_scan_reader;
  for (std::size_t i = 0; i < log.size(); ++i) {
    if (log.getType(i) != mrpt::obs::CRawlog::etObservation) continue;
    const auto obs = log.getAsObservation(i);
    Scan s;
    if (std::dynamic_pointer_cast<mrpt::obs::CObservationRotatingScan>(obs)) {
      // No conversion to points in MRPT 2.5: the plugin's own (ring elevations from its options).
      ObservationBeams beams;
      rotating_scan_reader.extractBeams(*obs, mrpt::poses::CPose3D(), beams, true);
      s.origin = beams.origin;
      s.points = std::move(beams.points);
    } else {
      // MRPT's own conversion to points in the robot frame (the sensor pose applied).
      mrpt::maps::CSimplePointsMap pm;
      pm.insertObservation(*obs);
      mrpt::poses::CPose3D sensor;
      obs->getSensorPose(sensor);
      s.origin = Eigen::Vector3d(sensor.x(), sensor.y(), sensor.z());
      const auto& xs = pm.getPointsBufferRef_x();
      const auto& ys = pm.getPointsBufferRef_y();
      const auto& zs = pm.getPointsBufferRef_z();
      for (std::size_t k = 0; k < xs.size(); ++k) s.points.emplace_back(xs[k], ys[k], zs[k]);
    }
    if (!s.points.empty()) d.scans.push_back(std::move(s));
  }
  if (d.scans.empty()) throw std::runtime_error(path + ": no 3D scans");
  return d;
}

void run2D(const std::string& rawlog, const Options& opts, std::vector<Result>& out, std::ostream& log) {
  mrpt::obs::CRawlog rl;
  if (!rl.loadFromRawLogFile(rawlog) || rl.size() == 0) throw std::runtime_error("cannot read rawlog " + rawlog);
  std::vector<std::pair<mrpt::poses::CPose3D, mrpt::obs::CObservation2DRangeScan::Ptr>> scans;
  forEachOdometryObservation(rl, [&](const mrpt::obs::CObservation::Ptr& obs, const mrpt::poses::CPose3D& robot,
                                     std::size_t) {
    if (auto scan = std::dynamic_pointer_cast<mrpt::obs::CObservation2DRangeScan>(obs)) scans.emplace_back(robot, scan);
  });
  const std::string name = "SENA 2D laser (" + std::to_string(scans.size()) + " scans)";
  std::size_t beams = 0;
  for (const auto& s : scans) beams += s.second->getScanSize();
  log << name << ": " << beams << " beams\n";
  const float max_range = 15.0f;  // COccupancyGridMap2D's default maxDistanceInsertion, for both
  constexpr int kLfDecimation = 5;  // COccupancyGridMap2D's default, set on both maps
  struct Method2D {
    std::string name;
    std::function<std::shared_ptr<mrpt::maps::CMetricMap>()> make;
    std::function<std::size_t(const mrpt::maps::CMetricMap&)> bytes;
    std::vector<double> times = {};
    std::shared_ptr<mrpt::maps::CMetricMap> map = nullptr;
    bool blur = false;  // each scan inserted at its pose with kPoseCov (poseUncertainty = on)
  };
  // The estimator's pose blur at odometry-like uncertainty: 0.05 m in x and y, 1 deg in yaw.
  mrpt::math::CMatrixDouble66 pose_cov;
  pose_cov.setZero();
  pose_cov(0, 0) = pose_cov(1, 1) = 0.05 * 0.05;
  pose_cov(3, 3) = (M_PI / 180.0) * (M_PI / 180.0);
  for (const double res : opts.resolutions) {
    std::vector<Method2D> methods;
    // rtog's MRPT map type: `name` after the common prefix, its options set by `set`.
    const auto rtogMethod = [&](const std::string& name, std::function<void(CRTreeOccupancyGridMap::TInsertionOptions&)> set,
                                bool blur) {
      methods.push_back({"rtog (CRTreeOccupancyGridMap), " + name,
                         [=] {
                           CRTreeOccupancyGridMap::TInsertionOptions io;
                           io.maxDistanceInsertion = max_range;
                           set(io);
                           auto m = std::make_shared<CRTreeOccupancyGridMap>(res, io);
                           m->likelihoodOptions.LF_decimation = kLfDecimation;
                           return m;
                         },
                         [](const mrpt::maps::CMetricMap& m) {
                           return dynamic_cast<const CRTreeOccupancyGridMap&>(m).map().memoryBytes();
                         },
                         {}, nullptr, blur});
    };
    // Both update rules: mrpt_grid (the MRPT map types' default: COccupancyGridMap2D's cells) and
    // octomap (one update per cell and scan, OctoMap's clamping).
    for (const std::string preset : {"mrpt_grid", "octomap"})
      for (const std::string policy : {"equal", "clamped", "off"})
        rtogMethod(preset + ", merge " + policy, [=](auto& io) { io.sensorModelPreset = preset, io.mergePolicy = policy; },
                   false);
    // The estimator's models in both presets (merge equal): range noise at a laser's sigma, pose
    // blur, both (doc/range-noise.md, doc/pose-uncertainty.md; in mrpt_grid on the grid's raster).
    for (const std::string preset : {"mrpt_grid", "octomap"})
      for (const int model : {0, 1, 2}) {
        const bool noise = model != 1, blur = model != 0;
        const std::string what = noise && blur ? "range noise (sigma 0.02 m + 0.01 m/m), pose blur (sigma 0.05 m, 1 deg)"
                                 : noise       ? "range noise (sigma 0.02 m + 0.01 m/m)"
                                               : "pose blur (sigma 0.05 m, 1 deg)";
        rtogMethod(preset + ", merge equal, " + what,
                   [=](auto& io) {
                     io.sensorModelPreset = preset;
                     io.sensorModel = noise ? "rangeNoise" : "beam";
                     io.rangeNoiseStd = 0.02f;
                     io.rangeNoiseStdPerMeter = 0.01f;
                     io.poseUncertainty = blur;
                   },
                   blur);
      }
    methods.push_back({"MRPT COccupancyGridMap2D",
                       [=] {
                         auto g = std::make_shared<mrpt::maps::COccupancyGridMap2D>(-10.0f, 10.0f, -10.0f, 10.0f,
                                                                                    float(res));
                         g->insertionOptions.maxDistanceInsertion = max_range;
                         g->likelihoodOptions.LF_decimation = kLfDecimation;
                         return g;
                       },
                       [](const mrpt::maps::CMetricMap& m) {
                         const auto& g = dynamic_cast<const mrpt::maps::COccupancyGridMap2D&>(m);
                         return g.getRawMap().size() * sizeof(mrpt::maps::COccupancyGridMap2D::cellType);
                       }});
    methods.erase(std::remove_if(methods.begin(), methods.end(),
                                 [&](const Method2D& m) { return !selected(opts, m.name); }),
                  methods.end());
    std::vector<std::vector<double>> times(methods.size());
    buildInRounds(opts, times, [](std::size_t) { return true; }, [&](std::size_t k) {
      Method2D& m = methods[k];
      m.map = m.make();
      const auto t0 = Clock::now();
      if (m.blur) {
        auto& rtog_map = dynamic_cast<CRTreeOccupancyGridMap&>(*m.map);
        for (const auto& [pose, scan] : scans)
          rtog_map.insertObservation(*scan, mrpt::poses::CPose3DPDFGaussian(pose, pose_cov));
      } else {
        for (const auto& [pose, scan] : scans) m.map->insertObservation(*scan, pose);
      }
      // Until the map can be read: rtog covers the scans of its planar cache with leaves.
      if (auto* rtog_map = dynamic_cast<CRTreeOccupancyGridMap*>(m.map.get())) rtog_map->map().flush();
      return seconds(t0, Clock::now());
    });
    for (std::size_t k = 0; k < methods.size(); ++k) methods[k].times = std::move(times[k]);
    for (Method2D& m : methods) {
      Result r;
      r.dataset = name;
      r.method = m.name;
      r.resolution = res;
      r.insert_seconds = median(m.times);
      r.build_seconds = m.times;
      r.extra["repeats"] = double(m.times.size());
      r.points_per_second = double(beams) / r.insert_seconds;
      r.structure_bytes = m.bytes(*m.map);
      // Likelihood of every scan at its own pose: one pass to warm caches, then the median of
      // nine timed passes (one pass takes a few milliseconds: a single hiccup would decide it).
      double sink = 0;
      for (const auto& [pose, scan] : scans) sink += m.map->computeObservationLikelihood(*scan, pose);
      std::vector<double> passes;
      for (int pass = 0; pass < 9; ++pass) {
        const auto t0 = Clock::now();
        for (const auto& [pose, scan] : scans) sink += m.map->computeObservationLikelihood(*scan, pose);
        passes.push_back(seconds(t0, Clock::now()));
      }
      r.extra["likelihood_us_per_scan"] = median(passes) / double(scans.size()) * 1e6;
      r.extra["likelihood_sum"] = sink;
      measureCopies(*m.map, r);
      if (!m.blur) measureFrontiers(*m.map, r);
      log << "  " << std::left << std::setw(48) << m.name << " res " << res << ": " << r.insert_seconds << " s, "
          << r.extra["likelihood_us_per_scan"] << " us/likelihood\n";
      out.push_back(r);
    }
  }
}

std::size_t writeLogOddsRaster(const OccupancyMap& map, const std::string& path) {
  const Box bounds = map.keyBounds();
  if (bounds.isEmpty()) throw std::runtime_error("writeLogOddsRaster: empty map");
  const auto extent = [&](int a) { return static_cast<std::size_t>(std::int64_t{bounds.max[a]} - bounds.min[a] + 1); };
  const std::size_t nx = extent(0), ny = extent(1), nz = extent(2);
  std::vector<signed char> raster(nx * ny * nz, 0);
  map.forEachLeaf([&](const Box& b, float log_odds) {
    const long step = std::lround(log_odds * 20.0f);
    const auto value = static_cast<signed char>(step == 0 ? 1 : std::clamp<long>(step, -127, 127));
    const auto from = [&](std::int32_t c, int a) { return static_cast<std::size_t>(std::int64_t{c} - bounds.min[a]); };
    for (std::int32_t z = b.min.z; z <= b.max.z; ++z)
      for (std::int32_t y = b.min.y; y <= b.max.y; ++y) {
        const std::size_t first = (from(z, 2) * ny + from(y, 1)) * nx + from(b.min.x, 0);
        std::fill_n(raster.begin() + static_cast<std::ptrdiff_t>(first), b.max.x - b.min.x + 1, value);
      }
  });
  app::OutputSet files;
  files.add("--raster-dir", path)
      .write(reinterpret_cast<const char*>(raster.data()), static_cast<std::streamsize>(raster.size()));
  files.commit();
  return raster.size();
}

void runDataset(const Dataset& data, const Options& opts, std::vector<Result>& out, std::ostream& log) {
  for (const double res : opts.resolutions) {
    auto methods = methodsFor(data, res, opts);
    // Query points: random, inside the data's bounding box (fixed seed).
    Eigen::Vector3d lo = data.scans.front().origin, hi = lo;
    for (const Scan& s : data.scans)
      for (const auto& q : s.points) lo = lo.cwiseMin(q.cast<double>()), hi = hi.cwiseMax(q.cast<double>());
    std::mt19937 rng(1234);
    std::vector<Eigen::Vector3d> queries(opts.query_count);
    for (auto& q : queries)
      for (int a = 0; a < 3; ++a) q[a] = std::uniform_real_distribution<double>(lo[a], hi[a])(rng);

    // Heavy methods go in rounds of their own after the others: interleaved, the dense grid's
    // page faults and frees slowed the builds after it (rtog's 2-thread scaling on rot_scan
    // measured 1.45x with it, 2.13x without).
    std::vector<std::vector<double>> build_times(methods.size());
    std::vector<double> rss_growth(methods.size(), 0.0), stolen(methods.size(), 0.0),
        faults(methods.size(), 0.0);
    for (const bool heavy_phase : {false, true})
      buildInRounds(
          opts, build_times, [&](std::size_t k) { return methods[k]->heavy() == heavy_phase; },
          [&](std::size_t k) {
            const bool first = build_times[k].empty();
            if (first) malloc_trim(0);  // for the RSS growth; later builds reuse the heap, as a long run does
            const double rss0 = residentBytes();
            const double steal0 = stolenCpuSeconds(), faults0 = minorFaults();
            const double s = methods[k]->build(data);
            stolen[k] += stolenCpuSeconds() - steal0;
            faults[k] += minorFaults() - faults0;
            if (first) rss_growth[k] = residentBytes() - rss0;
            return s;
          });

    if (!opts.raster_dir.empty())
      for (const auto& m : methods)
        if (m->rtogMap()) {
          const std::string path = opts.raster_dir + "/" + slug(data.name + "_" + std::to_string(res)) + ".i8";
          const std::size_t cells = writeLogOddsRaster(*m->rtogMap(), path);
          log << "  raster of " << m->name() << ": " << path << ", " << cells << " bytes\n";
          break;
        }

    const octomap::OcTree* plain_octomap = nullptr;
    std::vector<std::size_t> rtog_rows;
    for (std::size_t k = 0; k < methods.size(); ++k) {
      const auto& m = methods[k];
      Result r;
      r.dataset = data.name;
      r.method = m->name();
      r.resolution = res;
      const std::vector<double>& times = build_times[k];
      r.rss_growth_bytes = rss_growth[k];
      r.insert_seconds = median(times);
      r.build_seconds = times;
      r.extra["repeats"] = double(times.size());
      // Share of the machine's CPU time taken by other guests during these builds (the steal
      // counter ticks in 10 ms steps: read it over all of a method's builds, not one).
      double timed = 0;
      for (const double t : times) timed += t;
      const double cpus = double(std::max(1u, std::thread::hardware_concurrency()));
      r.extra["steal_fraction"] = timed > 0 ? stolen[k] / (timed * cpus) : 0.0;
      r.extra["minor_faults_per_build"] = times.empty() ? 0.0 : faults[k] / double(times.size());
      if (m->calibration()) {
        r.extra["calibration"] = 1;
        log << "  " << std::left << std::setw(48) << r.method << " res " << res << ": " << std::fixed
            << std::setprecision(4) << r.insert_seconds << " s\n";
        log.unsetf(std::ios::floatfield);
        out.push_back(r);
        continue;
      }
      r.points_per_second = double(data.points()) / r.insert_seconds;
      r.structure_bytes = m->structureBytes();
      r.leaves = m->leaves();
      r.point_query_ns = m->queryNs(queries);
      r.file_bytes = m->fileBytes();
      if (m->octree() && r.method == "OctoMap") plain_octomap = m->octree();
      if (m->rtogMap()) {
        rtog_rows.push_back(out.size());
        r.extra["class_cover_leaves"] = double(m->rtogMap()->classCover().leaves());
      }
      log << "  " << std::left << std::setw(48) << r.method << " res " << res << ": " << std::fixed
          << std::setprecision(4) << r.insert_seconds << " s, " << std::setprecision(2)
          << r.structure_bytes / 1048576.0 << " MiB, " << r.leaves << " leaves\n";
      log.unsetf(std::ios::floatfield);
      out.push_back(r);
    }
    // Class agreement of each rtog map with plain OctoMap (same scans, same parameters).
    for (auto& m : methods) {
      if (!m->rtogMap() || !plain_octomap) continue;
      for (const std::size_t row : rtog_rows)
        if (out[row].method == m->name() && out[row].resolution == res)
          out[row].octomap_agreement = compareWithOctomap(*m->rtogMap(), *plain_octomap).ratio();
    }
  }
}

}  // namespace rtog::bench
