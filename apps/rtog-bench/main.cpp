// rtog-bench: run by hand on a quiet machine (Release build); not a test.
#include <iostream>

#include <CLI/CLI.hpp>

#include "bench.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rtog-bench: rtog vs OctoMap and MRPT grids on real data, side by side"};
  rtog::bench::Options opts;
  std::string tum = RTOG_DEFAULT_TUM_DIR, json = "benchmarks.json", markdown = "benchmarks.md", img_dir = ".";
  app.add_option("--tum", tum, "TUM depth sequence directory")->capture_default_str();
  app.add_option("--repeats", opts.repeats, "Builds per method (median reported)")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--resolutions", opts.resolutions, "Cell sizes [m]")->capture_default_str();
  app.add_option("--json", json, "JSON output")->capture_default_str();
  app.add_option("--markdown", markdown, "Markdown report")->capture_default_str();
  app.add_option("--img-dir", img_dir, "Directory for PNG plots")->capture_default_str()->check(CLI::ExistingDirectory);
  CLI11_PARSE(app, argc, argv);
  try {
    std::vector<rtog::bench::Result> results;
    const auto data = rtog::bench::loadTum(tum);
    std::cout << data.name << ": " << data.points() << " points\n";
    rtog::bench::runDataset(data, opts, results, std::cout);
    rtog::bench::writeJson(results, json);
    rtog::bench::writeMarkdown(results, markdown, img_dir);
    std::cout << "wrote " << json << ", " << markdown << "\n";
  } catch (const std::exception& e) {
    std::cerr << "rtog-bench: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
