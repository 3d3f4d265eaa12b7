// The report's sections for what the map is for: planning beside MRPT's PlannerSimple2D, and
// chunked builds joined by fusion.
#include <algorithm>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>

#include "bench.hpp"

namespace rtog::bench {
namespace {

double get(const Result& r, const char* key) {
  const auto it = r.extra.find(key);
  return it == r.extra.end() ? -1.0 : it->second;
}

}  // namespace

bool isTaskRow(const Result& r) {
  return r.extra.count("plan") > 0 || r.extra.count("chunks") > 0 || r.extra.count("app_row") > 0;
}

void writeTaskSections(const std::vector<Result>& results, std::ostream& md) {
  std::set<std::string> plans;
  bool chunks = false;
  for (const auto& r : results) {
    if (r.extra.count("plan")) plans.insert(r.dataset);
    chunks = chunks || r.extra.count("chunks");
  }
  if (!plans.empty()) {
    md << "\n## Risk-aware planning beside MRPT's PlannerSimple2D\n\n"
       << "The MRPT map at 0.05 m (its `.ini` defaults), robot radius 0.3 m, from where the robot stood first to where\n"
       << "it stood half-way. `PlannerSimple2D` is MRPT's wavefront on the map's 2D view (obstacles grown by the\n"
       << "radius); rtog's A* minimises Te · Σ P(occupied) + Ta · length (Ta 1), crossing the map's alike free cuboids\n"
       << "whole (the default) or cell by cell (`rtog plan --cells`): the same cost, fewer nodes expanded. Clearance\n"
       << "is the least distance of a path cell to an occupied cell's centre, by brute force over the map. Times are\n"
       << "medians of the rounds; rtog's graph (the band's columns, the radius, the cuboids) is built apart from the\n"
       << "search and timed as such.\n";
    for (const auto& ds : plans) {
      md << "\n### " << ds << "\n\n| method | length [m] | summed risk | least clearance [m] | graph [ms] | plan [ms] | "
            "nodes expanded | free cuboids crossed whole |\n|---|---|---|---|---|---|---|---|\n";
      for (const auto& r : results) {
        if (r.dataset != ds || !r.extra.count("plan")) continue;
        const bool ours = get(r, "expanded") >= 0;
        const auto num = [](double v, int digits) {
          std::ostringstream o;
          o << std::fixed << std::setprecision(digits) << v;
          return o.str();
        };
        md << "| " << r.method << " | " << num(get(r, "length_m"), 2) << " | " << (ours ? num(get(r, "risk"), 3) : "–")
           << " | " << num(get(r, "clearance_m"), 3) << " | " << (ours ? num(get(r, "grid_ms"), 1) : "–") << " | "
           << num(get(r, "plan_ms"), 1) << " | "
           << (ours ? std::to_string(std::size_t(get(r, "expanded"))) + " of " + std::to_string(std::size_t(get(r, "nodes")))
                    : std::string("–"))
           << " | " << (ours ? std::to_string(std::size_t(get(r, "cuboids"))) : std::string("–")) << " |\n";
        md.unsetf(std::ios::floatfield);
      }
    }
  }
  if (chunks) {
    md << "\n## Building in chunks: separate processes, joined by fusion\n\n"
       << "Fusion without clamping is exact (`doc/fusion.md`), so a log can be built in chunks by independent\n"
       << "`rtog build --scans A:B` processes (any batch scheduler) and joined by `rtog fuse`. Wall times, medians of\n"
       << "the rounds, each process fresh (starting, loading the log and writing its map included), every process\n"
       << "with rtog's default two threads. On this one 2-core machine the two chunks at once share its cores; on\n"
       << "two machines the wall time would be the slower chunk's alone plus the fusion, which the last columns\n"
       << "compute from the measured times (each chunk also run alone).\n\n"
       << "| log | resolution [m] | one process [s] | 2 chunk processes at once [s] | fuse [s] | chunks at once + fuse "
          "[s] | each chunk alone [s] | two machines: slower chunk + fuse [s] | one process / two machines |\n"
          "|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : results) {
      if (!r.extra.count("chunks")) continue;
      md << "| " << r.dataset << " | " << r.resolution << " | " << std::fixed << std::setprecision(3)
         << get(r, "one_process_s") << " | " << get(r, "two_chunks_s") << " | " << get(r, "fuse_s") << " | "
         << get(r, "chunked_total_s") << " | " << get(r, "first_chunk_s") << ", " << get(r, "second_chunk_s") << " | ";
      const double two_machines = std::max(get(r, "first_chunk_s"), get(r, "second_chunk_s")) + get(r, "fuse_s");
      md << two_machines << " | " << std::setprecision(2) << get(r, "one_process_s") / two_machines << "× |\n";
      md.unsetf(std::ios::floatfield);
    }
  }
}

}  // namespace rtog::bench
