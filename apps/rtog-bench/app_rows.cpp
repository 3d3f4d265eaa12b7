// The MRPT apps as processes: the rows app_rows.py measures (the real apps with the stock grid and
// rtog's map types, wall time and peak RSS), read from its JSON into the report's results, so that
// they are kept in the bench's JSON and rendered again with --from-json.
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bench.hpp"

namespace rtog::bench {

std::vector<Result> readAppRows(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read the app rows " + file);
  nlohmann::json rows;
  try {
    in >> rows;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("the app rows " + file + " are not JSON: " + e.what());
  }
  if (!rows.is_array()) throw std::runtime_error("the app rows " + file + " are not a list (app_rows.py --json)");
  std::vector<Result> out;
  try {
    for (const auto& row : rows) {
      Result r;
      r.dataset = "MRPT apps: " + row.at("log").get<std::string>();
      r.extra["app_row"] = row.value("ok", false) ? 1 : 0;
      r.extra["particles"] = row.contains("particles") && row["particles"].is_number() ? row["particles"].get<double>() : -1;
      // One row per app, map and particle count (a row replaces an earlier one of the same three).
      r.method = row.at("app").get<std::string>() + " | " + row.at("map").get<std::string>();
      if (r.extra["particles"] >= 0) r.method += " | " + std::to_string(static_cast<long>(r.extra["particles"])) + " particles";
      for (const char* key : {"wall_s", "peak_rss_mb", "wall_ratio", "rss_ratio", "path_mean_m", "path_max_m",
                              "final_path_mean_m", "final_path_max_m", "repeats"})
        if (row.contains(key) && row[key].is_number()) r.extra[key] = row[key].get<double>();
      out.push_back(std::move(r));
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("the app rows " + file + ": " + e.what());
  }
  return out;
}

void writeAppRows(const std::vector<Result>& results, std::ostream& md) {
  bool any = false;
  for (const auto& r : results) any = any || r.extra.count("app_row");
  if (!any) return;
  md << "\n## The MRPT apps as processes\n\n"
     << "What a user meets: the real apps as Debian ships them, their stock configs (windows and periodic logs\n"
     << "off), the grid section pasted as rtog's map types and nothing else changed, the plugin preloaded. Every\n"
     << "run has MRPT's clock-seeded generator pinned (the tests' seed shim, `RTOG_TEST_SEED=1`), so the paths\n"
     << "can be compared. Wall time and peak RSS are `/usr/bin/time`'s, the median of the repeats; ratios are to\n"
     << "the stock grid of the same app, log and particle count; the path is the running estimate at every step\n"
     << "(`log_estimated_path.txt`) against the stock grid's. Measured by `apps/rtog-bench/app_rows.py` (its\n"
     << "`--json` given to `rtog-bench --app-rows`). A log not among Debian's datasets is one `rtog-simlog` made\n"
     << "(`doc/simlog.md`): `malaga_loop.rawlog`, 3,000 scans along a loop through the Malaga campus `.gridmap`.\n\n"
     << "| app | log | particles | map | wall [s] | peak RSS [MB] | path vs stock grid, mean / max [m] | runs |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  const auto num = [](double v, int digits) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << v;
    return o.str();
  };
  for (const auto& r : results) {
    if (!r.extra.count("app_row")) continue;
    const auto get = [&](const char* k) { return r.extra.count(k) ? r.extra.at(k) : -1.0; };
    const std::size_t bar = r.method.find(" | "), bar2 = r.method.find(" | ", bar + 3);
    md << "| " << r.method.substr(0, bar) << " | " << r.dataset.substr(std::string("MRPT apps: ").size()) << " | "
       << (get("particles") >= 0 ? num(get("particles"), 0) : "–") << " | `"
       << r.method.substr(bar + 3, bar2 == std::string::npos ? std::string::npos : bar2 - bar - 3) << "` | ";
    if (get("app_row") == 0) {
      md << "failed | – | – | – |\n";
      continue;
    }
    md << num(get("wall_s"), 2) << (get("wall_ratio") >= 0 ? " (" + num(get("wall_ratio"), 2) + "×)" : "") << " | "
       << num(get("peak_rss_mb"), 0) << (get("rss_ratio") >= 0 ? " (" + num(get("rss_ratio"), 2) + "×)" : "") << " | "
       << (get("path_mean_m") >= 0 ? num(get("path_mean_m"), 3) + " / " + num(get("path_max_m"), 3) : "–") << " | "
       << num(get("repeats"), 0) << " |\n";
  }
}

}  // namespace rtog::bench
