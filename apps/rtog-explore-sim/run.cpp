// rtog-explore-sim's runs, JSON and plot.
#include "run.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <cstdio>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "rtog/app/output_files.hpp"
#include "rtog/image/picture.hpp"
#include "rtog/sim/exploration.hpp"

namespace rtog::explore_sim {
namespace {

using sim::ExploreStrategy;
using sim::ExplorationStep;


void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.45, cv::Scalar c = {0, 0, 0}) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, 1, cv::LINE_AA);
}

/// One world's panel: coverage [0, 1] against the path [m] (or the views, `by_views`), both
/// strategies, the 90 % line.
void panel(cv::Mat& img, cv::Rect a, std::uint32_t seed, const std::vector<ExplorationStep> runs[2], double max_m,
           bool by_views) {
  cv::rectangle(img, a, cv::Scalar(0, 0, 0), 1);
  const auto px = [&](double m, double c) {
    return cv::Point(a.x + static_cast<int>(m / max_m * a.width), a.y + a.height - static_cast<int>(c * a.height));
  };
  cv::line(img, px(0, 0.9), px(max_m, 0.9), cv::Scalar(180, 180, 180), 1);
  const cv::Scalar colour[2] = {{200, 110, 20}, {40, 40, 220}};  // nearest frontier blue, information gain red
  for (int s = 0; s < 2; ++s)
    for (std::size_t i = 1; i < runs[s].size(); ++i) {
      const ExplorationStep &p = runs[s][i - 1], &q = runs[s][i];
      const double xp = by_views ? p.step : p.path_length, xq = by_views ? q.step : q.path_length;
      // Coverage grows at the step's end (the scans along the way are counted there).
      cv::line(img, px(xp, p.coverage), px(xq, p.coverage), colour[s], 2, cv::LINE_AA);
      cv::line(img, px(xq, p.coverage), px(xq, q.coverage), colour[s], 2, cv::LINE_AA);
    }
  text(img, "world " + std::to_string(seed), cv::Point(a.x + 8, a.y + 18));
  const int tick = by_views ? 5 : 10;
  for (int m = 0; m <= max_m; m += tick) text(img, std::to_string(m), cv::Point(px(m, 0).x - 6, a.y + a.height + 16), 0.4);
  text(img, "0.9", cv::Point(a.x - 28, px(0, 0.9).y + 4), 0.4);
  text(img, "0", cv::Point(a.x - 14, px(0, 0).y + 4), 0.4);
  text(img, "1", cv::Point(a.x - 14, px(0, 1).y + 8), 0.4);
}

}  // namespace

int run(const Config& c, std::ostream& out) {
  app::OutputSet files;
  std::ostream& json_out = files.add("--json", c.json_path);
  std::ostream* png = c.png_path.empty() ? nullptr : &files.add("--png", c.png_path);
  std::ostream* views_png = c.views_png_path.empty() ? nullptr : &files.add("--views-png", c.views_png_path);
  nlohmann::json j = nlohmann::json::array();
  std::vector<std::vector<ExplorationStep>> all;
  char line[200];
  for (std::uint32_t w = 0; w < c.worlds; ++w) {
    const std::uint32_t seed = c.first_seed + w;
    const sim::World world = sim::World::generate(sim::WorldParams{}, seed);
    nlohmann::json jw{{"seed", seed}};
    for (const ExploreStrategy s : {ExploreStrategy::NearestFrontier, ExploreStrategy::InformationGain}) {
      const std::vector<ExplorationStep> steps = sim::explore(world, s, sim::ExplorationParams::indoor());
      const std::string name = s == ExploreStrategy::InformationGain ? "information_gain" : "nearest_frontier";
      nlohmann::json js = nlohmann::json::array();
      for (const auto& st : steps) js.push_back({{"step", st.step}, {"path_m", st.path_length}, {"coverage", st.coverage}, {"scans", st.scans}});
      jw[name] = {{"steps", js}, {"metres_to_90", sim::lengthToCoverage(steps, 0.9)}};
      std::snprintf(line, sizeof line, "world %u, %-16s: %2zu views, %5.1f m, coverage %.3f, 90 %% at %5.1f m\n", seed,
                    name.c_str(), steps.size() - 1, steps.back().path_length, steps.back().coverage,
                    sim::lengthToCoverage(steps, 0.9));
      out << line;
      all.push_back(steps);
    }
    j.push_back(jw);
  }
  json_out << j.dump(1) << "\n";
  const auto plot = [&](bool by_views) {
    const int cols = 3, rows = static_cast<int>((c.worlds + 2) / 3), pw = 300, ph = 200;
    cv::Mat img(rows * (ph + 50) + 60, cols * (pw + 50) + 40, CV_8UC3, cv::Scalar(255, 255, 255));
    text(img, std::string("coverage of the free space against ") + (by_views ? "views driven to" : "path length [m]") +
                  ": nearest frontier (blue), information gain (red)",
         cv::Point(20, 24), 0.5);
    double max_x = 5.0;
    for (const auto& run : all) max_x = std::max(max_x, by_views ? double(run.back().step) : run.back().path_length);
    max_x = std::ceil(max_x / (by_views ? 5.0 : 10.0)) * (by_views ? 5.0 : 10.0);
    for (std::uint32_t w = 0; w < c.worlds; ++w) {
      const cv::Rect a(50 + static_cast<int>(w % 3) * (pw + 50), 50 + static_cast<int>(w / 3) * (ph + 50), pw, ph);
      const std::vector<ExplorationStep> runs[2] = {all[2 * w], all[2 * w + 1]};
      panel(img, a, c.first_seed + w, runs, max_x, by_views);
    }
    return image::encodePng(img);
  };
  for (const auto& [stream, by_views] : {std::pair{png, false}, std::pair{views_png, true}})
    if (stream) *stream << plot(by_views);
  files.commit();
  return 0;
}

}  // namespace rtog::explore_sim
