// rtog-explore-sim: nearest-frontier against information-gain exploration in seeded worlds.
#include <iostream>

#include <CLI/CLI.hpp>

#include "rtog/app/option_checks.hpp"
#include "run.hpp"

int main(int argc, char** argv) {
  rtog::explore_sim::Config c;
  CLI::App app{"rtog-explore-sim: closed-loop exploration of seeded worlds, nearest frontier against information gain"};
  app.add_option("--first-seed", c.first_seed, "The first world's seed")->capture_default_str();
  app.add_option("--worlds", c.worlds, "Worlds (seeds first-seed, first-seed + 1, ...)")
      ->capture_default_str()
      ->check(rtog::app::checks::integer(1, 100));
  app.add_option("--json", c.json_path, "Every step of every run")->required()->check(rtog::app::checks::path());
  app.add_option("--png", c.png_path, "Coverage against path length, a panel a world")->check(rtog::app::checks::path());
  app.add_option("--views-png", c.views_png_path, "Coverage against the views driven to")->check(rtog::app::checks::path());
  CLI11_PARSE(app, argc, argv);
  try {
    return rtog::explore_sim::run(c, std::cout);
  } catch (const std::exception& e) {
    std::cerr << "rtog-explore-sim: error: " << e.what() << "\n";
    return 1;
  }
}
