// Writes benchmark results: JSON for machines, Markdown + PNG plots for people.
#include <cctype>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "bench.hpp"
#include "first_scan.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/image/picture.hpp"

namespace rtog::bench {
namespace {

const Result* find(const std::vector<Result>& rs, const std::string& dataset, double res, const std::string& method) {
  for (const auto& r : rs)
    if (r.dataset == dataset && r.resolution == res && r.method == method) return &r;
  return nullptr;
}

/// A row of the estimator's models (range noise, pose blur): not a candidate of the plain targets.
bool estimatorRow(const Result& r) {
  return r.method.find("range noise") != std::string::npos || r.method.find("pose blur") != std::string::npos;
}

constexpr const char* kNoise = "range noise (sigma 0.02 m + 0.01 m/m)";
constexpr const char* kBlur = "pose blur (sigma 0.05 m, 1 deg)";

/// Issue #40's targets for the estimator's models: insertion against the plain model's, `base`
/// the plain row's name, `model(what)` the name of the row of the model `what`.
template <class Name>
void estimatorTargets(std::ostream& md, const std::vector<Result>& rs, const std::string& ds, double res,
                      const std::string& base, Name&& model) {
  const Result* plain = find(rs, ds, res, base);
  if (!plain) return;
  const std::string both = std::string(kNoise) + ", " + kBlur;
  const std::pair<std::string, double> wanted[] = {{kNoise, 1.5}, {kBlur, 2.0}, {both, 3.0}};
  for (const auto& [what, limit] : wanted) {
    const Result* r = find(rs, ds, res, model(what));
    if (!r) continue;
    const double ratio = r->insert_seconds / plain->insert_seconds;
    md << "| " << ds << " | " << res << " | " << what << ": insertion ≤ " << limit << "× the plain model's (" << base
       << ") | " << std::setprecision(3) << ratio << "× | " << (ratio <= limit ? "PASS" : "FAIL") << " |\n";
  }
}

/// Fastest OctoMap variant on a dataset/resolution: the reference the targets use.
const Result* bestOctomap(const std::vector<Result>& rs, const std::string& dataset, double res) {
  const Result* best = nullptr;
  for (const auto& r : rs)
    if (r.dataset == dataset && r.resolution == res && r.method.rfind("OctoMap", 0) == 0 &&
        (!best || r.insert_seconds < best->insert_seconds))
      best = &r;
  return best;
}

void barChart(const std::vector<std::pair<std::string, double>>& bars, const std::string& title, std::ostream& png) {
  const int w = 900, row = 26, top = 40, left = 330;
  cv::Mat img(top + row * int(bars.size()) + 20, w, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(img, title, {10, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 0}, 1, cv::LINE_AA);
  double maxv = 0;
  for (const auto& b : bars) maxv = std::max(maxv, b.second);
  for (std::size_t i = 0; i < bars.size(); ++i) {
    const int y = top + row * int(i);
    const bool ours = bars[i].first.rfind("rtog", 0) == 0;
    const int len = maxv > 0 ? int((w - left - 90) * bars[i].second / maxv) : 0;
    cv::rectangle(img, {left, y + 4}, {left + std::max(len, 1), y + row - 4},
                  ours ? cv::Scalar(60, 140, 30) : cv::Scalar(180, 120, 40), cv::FILLED);
    cv::putText(img, bars[i].first, {8, y + 17}, cv::FONT_HERSHEY_SIMPLEX, 0.42, {0, 0, 0}, 1, cv::LINE_AA);
    std::ostringstream v;
    v << std::setprecision(3) << bars[i].second;
    cv::putText(img, v.str(), {left + len + 6, y + 17}, cv::FONT_HERSHEY_SIMPLEX, 0.42, {0, 0, 0}, 1, cv::LINE_AA);
  }
  png << image::encodePng(img);
}

/// The dataset and resolution pairs of the bench's own rows (the first-scan rows have their own).
std::set<std::pair<std::string, double>> benchGroups(const std::vector<Result>& results) {
  std::set<std::pair<std::string, double>> groups;
  for (const auto& r : results)
    if (!r.extra.count("first_scan") && !isTaskRow(r)) groups.insert({r.dataset, r.resolution});
  return groups;
}

}  // namespace

std::string slug(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

RunInfo currentRun(const Options& opts) {
  RunInfo info;
  info.machine = machineFacts();
  info.repeats = opts.repeats;
  info.min_seconds = opts.min_seconds;
  return info;
}

void writeJson(const std::vector<Result>& results, const RunInfo& run, std::ostream& out) {
  nlohmann::json j;
  j["machine"] = run.machine;
  j["rounds"] = {{"repeats", run.repeats}, {"min_seconds", run.min_seconds}};
  for (const auto& r : results)
    j["results"].push_back({{"dataset", r.dataset},
                            {"method", r.method},
                            {"resolution", r.resolution},
                            {"insert_seconds_median", r.insert_seconds},
                            {"build_seconds", r.build_seconds},
                            {"points_per_second", r.points_per_second},
                            {"structure_bytes", r.structure_bytes},
                            {"rss_growth_bytes", r.rss_growth_bytes},
                            {"leaves", r.leaves},
                            {"point_query_ns", r.point_query_ns},
                            {"file_bytes", r.file_bytes},
                            {"octomap_class_agreement", r.octomap_agreement},
                            {"extra", r.extra}});
  out << j.dump(2) << "\n";
}

std::vector<Result> readJson(const std::string& path, RunInfo& run) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<Result> results;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    run = RunInfo{};
    run.machine = j.at("machine").get<std::map<std::string, std::string>>();
    if (j.contains("rounds")) {
      run.repeats = j["rounds"].at("repeats").get<int>();
      run.min_seconds = j["rounds"].at("min_seconds").get<double>();
    }
    for (const auto& e : j.at("results")) {
      Result r;
      r.dataset = e.at("dataset").get<std::string>();
      r.method = e.at("method").get<std::string>();
      r.resolution = e.at("resolution").get<double>();
      r.insert_seconds = e.at("insert_seconds_median").get<double>();
      r.build_seconds = e.at("build_seconds").get<std::vector<double>>();
      r.points_per_second = e.at("points_per_second").get<double>();
      r.structure_bytes = e.at("structure_bytes").get<std::size_t>();
      r.rss_growth_bytes = e.at("rss_growth_bytes").get<double>();
      r.leaves = e.at("leaves").get<std::size_t>();
      r.point_query_ns = e.at("point_query_ns").get<double>();
      r.file_bytes = e.at("file_bytes").get<std::size_t>();
      r.octomap_agreement = e.at("octomap_class_agreement").get<double>();
      r.extra = e.at("extra").get<std::map<std::string, double>>();
      results.push_back(std::move(r));
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a benchmark JSON file (" + e.what() + ")");
  }
  return results;
}

void writeMarkdown(const std::vector<Result>& results, const RunInfo& run, std::ostream& md,
                   const std::string& img_dir, app::OutputSet& files) {
  const auto field = [&](const char* key) {
    const auto it = run.machine.find(key);
    return it == run.machine.end() ? std::string("?") : it->second;
  };
  md << "# Benchmarks\n\nMeasured by `rtog-bench` (Release build), every method in one process on the same scans,\n"
     << "resolution and sensor model (OctoMap's defaults). Insertion time is the median of the builds of "
     << run.repeats << "\nrounds. Every method builds in every round, a fast one again until "
     << run.min_seconds / run.repeats << " s of its builds were timed\nin that round (at most "
     << std::max(1, kMaxBuilds / run.repeats) << " builds a round; the count is in the JSON), the fast methods taking "
        "turns\nbuild by build, so that all methods' builds sample the same slow spells of the machine and their "
        "ratios\nhold. The dense 3D grid (up to 1.7 GB a build) goes in\n"
     << "rounds of its own after the others, as its paging slowed the builds\n"
     << "that followed it. The heap is trimmed before each method's first 3D build only, for its RSS growth;\n"
     << "later builds reuse it, as a long-running process does. A build ends\n"
     << "when the map can be read: rtog's timed build includes covering its planar cache (2D scans). The 2D\n"
     << "likelihood figure is the median of nine passes over all scans, after one pass to fill caches.\n\n"
     << "The machine is a shared 2-vCPU VM with spells in which two busy vCPUs each run slower than one.\n"
     << "So beside the two-thread scaling stands what the machine gave two threads of the same work in\n"
     << "the same rounds: the throughput of two independent one-thread builds at once over that of one\n"
     << "(a yardstick, not a bound: two maps fill twice the cache one shared map does); and the steal,\n"
     << "the share of the vCPUs' time the hypervisor gave others during the two-thread builds (/proc/stat).\n\n"
     << "Machine: " << field("cpu") << ", " << field("cores") << " cores, " << field("memory") << " RAM"
     << (run.machine.count("os") ? ", " + field("os") : std::string()) << "; " << field("compiler") << "; OctoMap " << field("octomap") << ", MRPT " << field("mrpt") << "; "
     << field("date") << ".\n\n"
     << (run.machine.count("merged_rows_date")
             ? "This run measured some datasets only (`--only`); the rows of the others are those of the runs of " +
                   field("merged_rows_date") +
                   (!run.machine.count("merged_rows_cpu") || field("merged_rows_cpu") == field("cpu")
                        ? " on the same machine"
                        : ", on a machine with " + field("merged_rows_cpu") + " (so ratios compare within a dataset, not across)") +
                   " (`--merge-json`).\n\n"
             : std::string())
     << "Reproduce: `./build/apps/rtog-bench/rtog-bench"
     << (run.repeats != Options{}.repeats ? " --repeats " + std::to_string(run.repeats) : std::string())
     << (run.min_seconds != Options{}.min_seconds ? " --min-seconds " + [&] {
           std::ostringstream v;
           v << run.min_seconds;
           return v.str();
         }() : std::string())
     << " --markdown doc/benchmarks.md --json doc/benchmarks.json "
        "--img-dir doc/img`; to render this report again from the JSON without measuring, "
        "`--from-json doc/benchmarks.json` in place of `--json`.\n\n";

  const auto groups = benchGroups(results);

  md << "## Targets\n\n| dataset | res | target | measured | verdict |\n|---|---|---|---|---|\n";
  for (const auto& [ds, res] : groups) {
    const Result* oct = bestOctomap(results, ds, res);
    const Result* beam = find(results, ds, res, "rtog beam, merge equal");
    const Result* beam2 = find(results, ds, res, "rtog beam, merge equal, 2 threads");
    const Result* disc2 = find(results, ds, res, "rtog beam discretize, merge equal, 2 threads");
    const Result* octplain = find(results, ds, res, "OctoMap");
    const Result* dense = find(results, ds, res, "MRPT COccupancyGridMap3D (dense)");
    const Result* grid2d = find(results, ds, res, "MRPT COccupancyGridMap2D");
    // The 2D targets take rtog's best merge policy for each figure, and name it.
    const Result *rtog2d_ins = nullptr, *rtog2d_lik = nullptr;
    for (const auto& r : results) {
      if (r.dataset != ds || r.resolution != res || r.method.rfind("rtog (CRTreeOccupancyGridMap)", 0) != 0 ||
          estimatorRow(r))
        continue;
      if (!rtog2d_ins || r.insert_seconds < rtog2d_ins->insert_seconds) rtog2d_ins = &r;
      if (!rtog2d_lik || r.extra.at("likelihood_us_per_scan") < rtog2d_lik->extra.at("likelihood_us_per_scan"))
        rtog2d_lik = &r;
    }
    // The mrpt_grid preset, which gives the grid's cells: its own targets.
    const Result *grid_ins = nullptr, *grid_lik = nullptr;
    for (const auto& r : results) {
      if (r.dataset != ds || r.resolution != res || r.method.rfind("rtog (CRTreeOccupancyGridMap), mrpt_grid", 0) != 0 ||
          estimatorRow(r))
        continue;
      if (!grid_ins || r.insert_seconds < grid_ins->insert_seconds) grid_ins = &r;
      if (!grid_lik || r.extra.at("likelihood_us_per_scan") < grid_lik->extra.at("likelihood_us_per_scan"))
        grid_lik = &r;
    }
    if (grid2d && grid_ins) {
      const double ins = grid_ins->insert_seconds / grid2d->insert_seconds;
      const double lik = grid_lik->extra.at("likelihood_us_per_scan") / grid2d->extra.at("likelihood_us_per_scan");
      md << "| " << ds << " | " << res << " | mrpt_grid 2D insertion time ≤ 1.5× COccupancyGridMap2D (" << grid_ins->method
         << ") | " << std::setprecision(3) << ins << "× | " << (ins <= 1.5 ? "PASS" : "FAIL") << " |\n";
      md << "| " << ds << " | " << res << " | mrpt_grid LF likelihood time per scan ≤ 1× COccupancyGridMap2D ("
         << grid_lik->method << ") | " << std::setprecision(3) << lik << "× | " << (lik <= 1.0 ? "PASS" : "FAIL")
         << " |\n";
    }
    if (grid2d && grid_ins && grid2d->extra.count("copy_us")) {
      // The map copy a particle filter makes per particle when it resamples.
      const Result* copy = nullptr;
      for (const auto& r : results)
        if (r.dataset == ds && r.resolution == res && r.method.rfind("rtog (CRTreeOccupancyGridMap), mrpt_grid", 0) == 0 &&
            !estimatorRow(r) && r.extra.count("copy_us") && (!copy || r.extra.at("copy_us") < copy->extra.at("copy_us")))
          copy = &r;
      const double ratio = copy->extra.at("copy_us") / grid2d->extra.at("copy_us");
      md << "| " << ds << " | " << res << " | map copy time ≤ 1/100 of COccupancyGridMap2D's (" << copy->method << ": "
         << std::setprecision(3) << copy->extra.at("copy_us") << " µs, " << copy->extra.at("copy_heap_bytes") / 1024.0
         << " KiB held; the grid " << grid2d->extra.at("copy_us") << " µs, "
         << grid2d->extra.at("copy_heap_bytes") / 1048576.0 << " MiB) | " << std::setprecision(3) << ratio << "× | "
         << (ratio <= 0.01 ? "PASS" : "FAIL") << " |\n";
    }
    if (grid2d && grid2d->extra.count("frontier_ms")) {
      // Exploration's first step: the 2D frontier, from the cuboids against a dense scan of the grid.
      for (const auto& r : results) {
        if (r.dataset != ds || r.resolution != res || estimatorRow(r) || !r.extra.count("frontier_ms") ||
            r.method.rfind("rtog (CRTreeOccupancyGridMap)", 0) != 0)
          continue;
        const double ratio = r.extra.at("frontier_ms") / grid2d->extra.at("frontier_ms");
        md << "| " << ds << " | " << res << " | 2D frontier from cuboids against a dense scan of COccupancyGridMap2D ("
           << r.method << ": " << std::setprecision(3) << r.extra.at("frontier_ms") << " ms, "
           << r.extra.at("frontier_cells") << " cells; the grid " << grid2d->extra.at("frontier_ms") << " ms, "
           << grid2d->extra.at("frontier_cells") << " cells) | " << ratio << "× | – (a figure) |\n";
      }
    }
    if (grid2d && rtog2d_ins) {
      const double ins = rtog2d_ins->insert_seconds / grid2d->insert_seconds;
      const double lik =
          rtog2d_lik->extra.at("likelihood_us_per_scan") / grid2d->extra.at("likelihood_us_per_scan");
      md << "| " << ds << " | " << res << " | 2D insertion time ≤ 2× COccupancyGridMap2D (" << rtog2d_ins->method
         << ") | " << std::setprecision(3) << ins << "× | " << (ins <= 2.0 ? "PASS" : "FAIL") << " |\n";
      md << "| " << ds << " | " << res << " | LF likelihood time per scan ≤ 2× COccupancyGridMap2D ("
         << rtog2d_lik->method << ") | " << std::setprecision(3) << lik << "× | " << (lik <= 2.0 ? "PASS" : "FAIL")
         << " |\n";
    }
    for (const std::string preset : {"mrpt_grid", "octomap"}) {
      const std::string base = "rtog (CRTreeOccupancyGridMap), " + preset + ", merge equal";
      estimatorTargets(md, results, ds, res, base, [&](const std::string& what) { return base + ", " + what; });
    }
    estimatorTargets(md, results, ds, res, "rtog beam, merge equal", [](const std::string& what) {
      return what == kBlur ? "rtog beam, " + what + ", merge equal" : "rtog " + what + ", merge equal";
    });
    if (!oct || !beam) continue;
    // C++17 lambdas cannot capture structured bindings (clang rejects it; C++20 allows it).
    const auto row = [&, &ds = ds, &res = res](const std::string& target, double value, bool pass,
                                               const std::string& unit, const char* not_a_target = nullptr) {
      md << "| " << ds << " | " << res << " | " << target << " | " << std::setprecision(3) << value << unit << " | "
         << (not_a_target ? not_a_target : pass ? "PASS" : "FAIL") << " |\n";
    };
    // The issue sets the insertion-speed target at 0.05 m; other resolutions are shown for reference.
    const char* speed_scope = std::abs(res - 0.05) < 1e-9 ? nullptr : "– (target set at 0.05 m)";
    const Result* fastest = beam;
    for (const Result* c : {beam2, disc2})
      if (c && c->insert_seconds < fastest->insert_seconds) fastest = c;
    row("insertion ≥ 20× faster than OctoMap's best (" + oct->method + "), best rtog mode (" + fastest->method + ")",
        oct->insert_seconds / fastest->insert_seconds, oct->insert_seconds / fastest->insert_seconds >= 20.0, "×",
        speed_scope);
    // The same target on one thread, OctoMap having only one.
    const Result* disc = find(results, ds, res, "rtog beam discretize, merge equal");
    const Result* fastest1 = disc && disc->insert_seconds < beam->insert_seconds ? disc : beam;
    row("insertion ≥ 20× faster than OctoMap's best, on one thread (" + fastest1->method + ")",
        oct->insert_seconds / fastest1->insert_seconds, oct->insert_seconds / fastest1->insert_seconds >= 20.0, "×",
        speed_scope);
    if (octplain)
      row("memory ≤ 0.5× OctoMap memoryUsage()", double(beam->structure_bytes) / double(octplain->structure_bytes),
          double(beam->structure_bytes) <= 0.5 * double(octplain->structure_bytes), "×");
    if (dense)
      row("stretch: insertion within 2× of the dense 3D grid's time (best rtog mode)",
          fastest->insert_seconds / dense->insert_seconds, fastest->insert_seconds <= 2.0 * dense->insert_seconds, "×");
    if (dense) {
      // How far dropping the log-odds would go: the class-only cover's cuboids at 3 bytes each
      // (two corners in a 16^3 brick), with no tree, brick keys or values.
      std::ostringstream context;
      if (beam->extra.count("class_cover_leaves"))
        context << " (classes only, 3 bytes a cuboid: " << std::setprecision(2)
                << 3.0 * beam->extra.at("class_cover_leaves") / double(dense->structure_bytes) << "×)";
      row("memory ≤ 1/100 of the dense 3D grid", double(beam->structure_bytes) / double(dense->structure_bytes),
          double(beam->structure_bytes) * 100.0 <= double(dense->structure_bytes), "×" + context.str());
    }
    if (beam2) {
      // What the machine gave two threads of this work in the same rounds (two independent builds
      // at once), and the steal during the two-thread builds: a ratio measured on a shared VM
      // needs both to be read.
      std::ostringstream context;
      if (const Result* pair = find(results, ds, res, "rtog beam, merge equal, two 1-thread builds at once"))
        context << " (two 1-thread builds at once: " << std::setprecision(3)
                << 2.0 * beam->insert_seconds / pair->insert_seconds << "×; steal " << std::setprecision(2)
                << 100.0 * beam2->extra.at("steal_fraction") << " %)";
      row("--threads 2 throughput ≥ 1.7× of 1 thread", beam->insert_seconds / beam2->insert_seconds,
          beam->insert_seconds / beam2->insert_seconds >= 1.7, "×" + context.str());
    }
  }

  writeFirstScanTargets(results, md);

  for (const auto& [ds, res] : groups) {
    md << "\n## " << ds << ", " << res << " m\n\n"
       << "| method | insert [s] | M points/s | structure [MiB] | RSS growth [MiB] | leaves | point query [ns] | file [MiB] "
          "| class agreement with OctoMap | LF likelihood [µs/scan] |\n|---|---|---|---|---|---|---|---|---|---|\n";
    std::vector<std::pair<std::string, double>> bars;
    for (const auto& r : results) {
      if (r.dataset != ds || r.resolution != res || r.extra.count("calibration") || r.extra.count("first_scan"))
        continue;
      md << "| " << r.method << " | " << std::fixed << std::setprecision(4) << r.insert_seconds << " | "
         << std::setprecision(2) << r.points_per_second / 1e6 << " | " << std::setprecision(2)
         << r.structure_bytes / 1048576.0 << " | " << r.rss_growth_bytes / 1048576.0 << " | " << r.leaves << " | "
         << std::setprecision(0) << r.point_query_ns << " | " << std::setprecision(2)
         << (r.file_bytes ? std::to_string(r.file_bytes / 1048576.0).substr(0, 5) : std::string("–")) << " | "
         << (r.octomap_agreement >= 0 ? std::to_string(100.0 * r.octomap_agreement).substr(0, 6) + " %"
                                      : std::string("–"))
         << " | "
         << (r.extra.count("likelihood_us_per_scan") ? std::to_string(r.extra.at("likelihood_us_per_scan")).substr(0, 6)
                                                     : std::string("–"))
         << " |\n";
      md.unsetf(std::ios::floatfield);
      bars.push_back({r.method, r.insert_seconds});
    }
    const std::string img = slug(ds) + "_" + slug(std::to_string(res)) + "_insert.png";
    barChart(bars, "insertion time [s], " + ds + ", " + std::to_string(res).substr(0, 4) + " m",
             files.add("--img-dir", img_dir + "/" + img));
    md << "\n![insertion time](img/" << img << ")\n";
  }
  writeFirstScanSection(results, md);
  writeTaskSections(results, md);
  writeAppRows(results, md);
  md << "\n## Accuracy against ground truth\n\n"
     << "Speed and memory say nothing about how good a map is: `rtog-accuracy` builds rtog, OctoMap and\n"
     << "MRPT's dense grids from simulated LiDAR and 2D scans of a seeded synthetic world whose occupancy is\n"
     << "known, and scores precision/recall and ROC AUC. Figures and how to reproduce them: `doc/accuracy.md`.\n\n"
     << "![ROC curves against the synthetic ground truth](img/roc_synthetic.png)\n";
}

}  // namespace rtog::bench
