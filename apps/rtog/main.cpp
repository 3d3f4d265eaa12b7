// rtog: build and inspect R-tree occupancy grids.
#include <iostream>

#include <CLI/CLI.hpp>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rtog: R-tree occupancy grids for MRPT"};
  app.require_subcommand(1);

  rtog::cli::BuildTumOptions build;
  std::string model = "beam", merge = "clamped";
  auto* b = app.add_subcommand("build", "Build a map from real sensor data");
  b->add_option("--tum", build.tum_dir, "TUM RGB-D depth sequence directory")->required()->check(CLI::ExistingDirectory);
  b->add_option("--out", build.out_path, "Output map (.rtog)");
  b->add_option("--resolution", build.map.resolution, "Cell size [m]")->capture_default_str()->check(CLI::PositiveNumber);
  b->add_option("--model", model, "Sensor model: beam | endpoint")->capture_default_str();
  b->add_option("--merge", merge, "Leaf merging: off | clamped | equal")->capture_default_str();
  b->add_option("--max-range", build.insert.max_range, "Cut beams longer than this [m] (<= 0: no limit)");
  b->add_option("--threads", build.insert.threads, "Threads tracing beams")->capture_default_str()->check(CLI::Range(1, 256));
  b->add_flag("--discretize", build.insert.discretize, "Trace beams to end-cell centres, once per cell (OctoMap's discretize)");
  b->add_option("--stride", build.stride, "Use every n-th pixel")->capture_default_str()->check(CLI::PositiveNumber);

  std::string map_path;
  bool json = false;
  auto* i = app.add_subcommand("info", "Print a map's statistics");
  i->add_option("map", map_path, "Map file (.rtog)")->required();
  i->add_flag("--json", json, "JSON output");

  CLI11_PARSE(app, argc, argv);
  try {
    if (b->parsed()) {
      build.insert.model = rtog::sensorModelFromString(model);
      build.map.merge = rtog::mergePolicyFromString(merge);
      return rtog::cli::buildFromTum(build, std::cout);
    }
    return rtog::cli::info(map_path, json, std::cout);
  } catch (const std::exception& e) {
    std::cerr << "rtog: error: " << e.what() << "\n";
    return 1;
  }
}
