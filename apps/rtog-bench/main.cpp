// rtog-bench: run by hand on a quiet machine (Release build); not a test.
#include <algorithm>
#include <iostream>

#include <CLI/CLI.hpp>

#include "bench.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rtog-bench: rtog vs OctoMap and MRPT grids on real data, side by side"};
  rtog::bench::Options opts;
  std::string datasets_dir = "/usr/share/mrpt/datasets";
  std::vector<std::string> only;
  std::string tum = RTOG_DEFAULT_TUM_DIR, json = "benchmarks.json", markdown = "benchmarks.md", img_dir = ".";
  app.add_option("--tum", tum, "TUM depth sequence directory")->capture_default_str();
  app.add_option("--mrpt-datasets", datasets_dir, "Debian mrpt-common datasets directory")->capture_default_str();
  app.add_option("--only", only, "Run only these datasets: tum, vlp16, rotscan, sena");
  app.add_option("--methods", opts.methods, "Run only methods whose name contains one of these (profiling)");
  app.add_option("--repeats", opts.repeats, "Rounds of builds, every method in each (median reported)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--min-seconds", opts.min_seconds,
                 "A fast method builds again in a round until its share of this much was timed")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--resolutions", opts.resolutions, "Cell sizes [m]")->capture_default_str();
  app.add_option("--json", json, "JSON output")->capture_default_str();
  app.add_option("--markdown", markdown, "Markdown report")->capture_default_str();
  app.add_option("--img-dir", img_dir, "Directory for PNG plots")->capture_default_str()->check(CLI::ExistingDirectory);
  std::string from_json;
  app.add_option("--from-json", from_json, "Render the Markdown report and plots from this JSON; measure nothing")
      ->check(CLI::ExistingFile);
  app.add_option("--raster-dir", opts.raster_dir, "Write each dataset's first rtog map as a byte-per-cell raster here")
      ->check(CLI::ExistingDirectory);
  CLI11_PARSE(app, argc, argv);
  try {
    if (!from_json.empty()) {
      rtog::bench::RunInfo run;
      const auto results = rtog::bench::readJson(from_json, run);
      rtog::bench::writeMarkdown(results, run, markdown, img_dir);
      std::cout << "wrote " << markdown << " from " << from_json << "\n";
      return 0;
    }
    const rtog::bench::RunInfo run = rtog::bench::currentRun(opts);
    std::vector<rtog::bench::Result> results;
    const auto wanted = [&](const std::string& n) { return only.empty() || std::find(only.begin(), only.end(), n) != only.end(); };
    std::vector<rtog::bench::Dataset> sets;
    if (wanted("tum")) sets.push_back(rtog::bench::loadTum(tum));
    if (wanted("vlp16"))
      sets.push_back(rtog::bench::loadRawlog3D(datasets_dir + "/test_velodyne_VLP16.rawlog", "Velodyne VLP-16 (test_velodyne_VLP16)"));
    if (wanted("rotscan"))
      sets.push_back(rtog::bench::loadRawlog3D(datasets_dir + "/rot_scan_velodyne.rawlog", "Velodyne rotating scan (rot_scan_velodyne)"));
    if (wanted("sena"))
      rtog::bench::run2D(datasets_dir + "/2006-01ENE-21-SENA_Telecom Faculty_one_loop_only.rawlog", opts, results, std::cout);
    for (const auto& data : sets) {
      std::cout << data.name << ": " << data.points() << " points\n";
      rtog::bench::runDataset(data, opts, results, std::cout);
    }
    rtog::bench::writeJson(results, run, json);
    rtog::bench::writeMarkdown(results, run, markdown, img_dir);
    std::cout << "wrote " << json << ", " << markdown << "\n";
  } catch (const std::exception& e) {
    std::cerr << "rtog-bench: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
