// The first-scan rows: the helper run as a fresh process per sample, medians, report.
#include "first_scan.hpp"

#include "process.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace rtog::bench {
namespace {

/// The start of a row's name: what an MRPT user writes in the .ini, and the class it makes.
std::string methodName(const FirstScanMap& m) {
  const std::string cls = m.type == "rtreeOccupancyGrid" ? "rtog CRTreeOccupancyGridMap"
                          : m.type == "octoMap"           ? "MRPT COctoMap"
                                                          : "MRPT COccupancyGridMap2D";
  return "first scan: " + m.type + " (" + cls + ")" + (m.as_recorded ? ", observation as recorded" : "");
}

}  // namespace

std::vector<FirstScanMap> firstScanMaps(const FirstScanSource& source) {
  std::vector<FirstScanMap> maps{{"rtreeOccupancyGrid", false}, {"octoMap", false}};
  if (source.kind == "rawlog2d")
    maps.push_back({"occupancyGrid", false});
  else
    maps.push_back({"rtreeOccupancyGrid", true});
  return maps;
}

FirstScanSample runFirstScanProcess(const std::string& helper, const FirstScanSource& source, const FirstScanMap& map,
                                    double resolution) {
  std::ostringstream res;
  res.precision(17);
  res << resolution;
  std::vector<std::string> args{helper, "--kind", source.kind, "--path", source.path, "--map", map.type,
                                "--resolution", res.str()};
  if (map.as_recorded) args.push_back("--as-recorded");
  const std::string text = runCapturingStdout(args, helper + " (" + methodName(map) + ", " + source.label + ")");
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    FirstScanSample s;
    s.observation = j.at("observation").get<std::string>();
    s.observation = s.observation.substr(s.observation.rfind(':') + 1);  // without mrpt::obs::
    s.create_seconds = j.at("create_seconds").get<double>();
    s.insert_seconds = j.at("insert_seconds").get<double>();
    s.heap_held_bytes = j.at("heap_held_bytes").get<double>();
    s.heap_held_uordblks = j.at("heap_held_uordblks").get<double>();
    s.map_bytes = j.at("map_bytes").get<std::size_t>();
    s.points = j.at("points").get<std::size_t>();
    return s;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(helper + " printed no sample (" + e.what() + "): " + text);
  }
}

void runFirstScans(const std::string& helper, const std::vector<FirstScanSource>& sources, const Options& opts,
                   std::vector<Result>& out, std::ostream& log) {
  for (const FirstScanSource& src : sources)
    for (const double res : opts.resolutions) {
      std::vector<FirstScanMap> maps;
      for (const auto& m : firstScanMaps(src))
        if (selected(opts, methodName(m))) maps.push_back(m);
      std::vector<std::vector<FirstScanSample>> samples(maps.size());
      for (int round = 0; round < opts.repeats; ++round)
        for (std::size_t k = 0; k < maps.size(); ++k)
          samples[k].push_back(runFirstScanProcess(helper, src, maps[k], res));
      for (std::size_t k = 0; k < maps.size(); ++k) {
        const auto medianOf = [&](auto field) {
          std::vector<double> v;
          for (const auto& s : samples[k]) v.push_back(double(field(s)));
          return median(v);
        };
        Result r;
        r.dataset = src.label;
        r.method = methodName(maps[k]) + ", from " + samples[k].front().observation;
        r.resolution = res;
        for (const auto& s : samples[k]) r.build_seconds.push_back(s.insert_seconds);
        r.insert_seconds = median(r.build_seconds);
        r.structure_bytes = static_cast<std::size_t>(medianOf([](const FirstScanSample& s) { return s.map_bytes; }));
        const double points = medianOf([](const FirstScanSample& s) { return s.points; });
        r.points_per_second = r.insert_seconds > 0 ? points / r.insert_seconds : 0.0;
        r.extra["first_scan"] = 1;
        r.extra["as_recorded"] = maps[k].as_recorded ? 1 : 0;
        r.extra["repeats"] = double(samples[k].size());
        r.extra["points"] = points;
        r.extra["create_seconds"] = medianOf([](const FirstScanSample& s) { return s.create_seconds; });
        r.extra["heap_held_bytes"] = medianOf([](const FirstScanSample& s) { return s.heap_held_bytes; });
        r.extra["heap_held_uordblks_bytes"] = medianOf([](const FirstScanSample& s) { return s.heap_held_uordblks; });
        log << "  " << std::left << std::setw(60) << r.method << " res " << res << ": " << std::fixed
            << std::setprecision(4) << r.insert_seconds << " s, heap held " << std::setprecision(2)
            << r.extra["heap_held_bytes"] / 1048576.0 << " MiB, map " << r.structure_bytes / 1048576.0 << " MiB\n";
        log.unsetf(std::ios::floatfield);
        out.push_back(std::move(r));
      }
    }
}

namespace {
/// The first-scan row of a map type on the observation every map type takes.
const Result* findRow(const std::vector<Result>& rs, const std::string& ds, double res, const std::string& type) {
  const std::string start = methodName({type, false});
  for (const auto& r : rs)
    if (r.dataset == ds && r.resolution == res && r.extra.count("first_scan") && r.extra.at("as_recorded") == 0 &&
        r.method.rfind(start + ", from ", 0) == 0)
      return &r;
  return nullptr;
}
std::set<std::pair<std::string, double>> firstScanGroups(const std::vector<Result>& results) {
  std::set<std::pair<std::string, double>> groups;
  for (const auto& r : results)
    if (r.extra.count("first_scan")) groups.insert({r.dataset, r.resolution});
  return groups;
}
}  // namespace

void writeFirstScanTargets(const std::vector<Result>& results, std::ostream& md) {
  for (const auto& [ds, res] : firstScanGroups(results)) {
    const Result* rtog = findRow(results, ds, res, "rtreeOccupancyGrid");
    const Result* octo = findRow(results, ds, res, "octoMap");
    if (!rtog) continue;
    if (octo && rtog->insert_seconds > 0) {
      const double ratio = octo->insert_seconds / rtog->insert_seconds;
      md << "| " << ds << " | " << res << " | first scan, fresh process, CMetricMap::insertObservation: ≥ 20× faster "
         << "than COctoMap's | " << std::setprecision(3) << ratio << "× | " << (ratio >= 20.0 ? "PASS" : "FAIL") << " |\n";
    }
    const double held = rtog->extra.at("heap_held_bytes"), own = double(rtog->structure_bytes);
    const double ratio = own > 0 ? held / own : 0.0;
    md << "| " << ds << " | " << res << " | heap held after the first scan ≤ 1.5× the map's memoryBytes() | "
       << std::setprecision(3) << ratio << "× (" << std::setprecision(2) << (held - own) / 1048576.0
       << " MiB beyond it) | " << (own > 0 && ratio <= 1.5 ? "PASS" : "FAIL") << " |\n";
  }
}

void writeFirstScanSection(const std::vector<Result>& results, std::ostream& md) {
  const auto groups = firstScanGroups(results);
  if (groups.empty()) return;
  double repeats = 0;
  for (const auto& r : results)
    if (r.extra.count("first_scan")) repeats = std::max(repeats, r.extra.at("repeats"));
  md << "\n## The first scan, as MRPT users meet it\n\n"
     << "Each figure is the median of " << repeats << " fresh processes (`rtog-first-scan`, the maps taking turns).\n"
     << "In each, a `CMultiMetricMap` is made from an `.ini` section (`<type>_count=1`, default options but\n"
     << "the resolution) and one observation goes in through `CMetricMap::insertObservation`: a TUM depth\n"
     << "frame, a rawlog's first observation, SENA's first 2D laser scan (at its odometry pose). MRPT 2.5's\n"
     << "`COctoMap` takes a depth image only with its points and no Velodyne packets, so those rows get\n"
     << "the observation in a form both maps take, made before the measurement: the depth image's points\n"
     << "(`unprojectInto`), the packets as a `CObservationPointCloud`; the rows \"as recorded\" give rtog the\n"
     << "observation as the file has it. Where the map types' defaults differ, so do the maps: rtog cuts\n"
     << "beams at 15 m (`maxDistanceInsertion`, as `COccupancyGridMap2D`), `COctoMap` traces them to their\n"
     << "end (`maxrange` −1), and rtog reads a depth image one pixel in 8 × 8 (`decimation_3d_range`; the\n"
     << "points column counts the observation's points). The heap held is glibc's bytes in use (`mallinfo2`\n"
     << "`uordblks` + `hblkhd`) after the call returned less before it: the map, and what the insertion\n"
     << "keeps (scratch buffers, caches, tables made on first use).\n\n"
     << "| dataset | res | map | first scan [ms] | points | map's own bytes [MiB] | heap held [MiB] | held / own | "
        "map creation [ms] |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [ds, res] : groups)
    for (const auto& r : results) {
      if (!r.extra.count("first_scan") || r.dataset != ds || r.resolution != res) continue;
      const double held = r.extra.at("heap_held_bytes");
      md << "| " << ds << " | " << res << " | " << r.method.substr(r.method.find(':') + 2) << " | " << std::fixed
         << std::setprecision(2) << 1e3 * r.insert_seconds << " | " << std::setprecision(0) << r.extra.at("points")
         << " | " << std::setprecision(2) << r.structure_bytes / 1048576.0 << " | " << held / 1048576.0 << " | "
         << (r.structure_bytes ? held / double(r.structure_bytes) : 0.0) << " | " << std::setprecision(3)
         << 1e3 * r.extra.at("create_seconds") << " |\n";
      md.unsetf(std::ios::floatfield);
    }
}

}  // namespace rtog::bench
