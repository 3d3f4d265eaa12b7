// rtog-explore-sim: both strategies on each world, written as JSON and drawn.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>

namespace rtog::explore_sim {

struct Config {
  std::uint32_t first_seed = 1, worlds = 6;
  std::string json_path, png_path, views_png_path;
};

/// Runs and writes the files (all or none); a table to `out`. Returns the exit code.
int run(const Config& c, std::ostream& out);

}  // namespace rtog::explore_sim
