// Reliability diagrams of the accuracy report, drawn with OpenCV: per bin of P(occupied), the
// share of truly occupied cells against the bin's mean P. A calibrated map lies on the diagonal;
// the marker area grows with the bin's share of the cells, since a bin of a few cells says little.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "accuracy.hpp"
#include "plot_common.hpp"
#include "rtog/image/picture.hpp"

namespace rtog::accuracy {

namespace {

void panel(cv::Mat& img, cv::Rect area, const Report& r, const Scenario& sc) {
  using plot::text;
  const int ml = 80, mr = 20, mt = 40, mb = 50;
  const cv::Rect box(area.x + ml, area.y + mt, area.width - ml - mr, area.height - mt - mb);
  auto px = [&](double x, double y) {
    return cv::Point(box.x + static_cast<int>(std::lround(x * box.width)),
                     box.y + box.height - static_cast<int>(std::lround(y * box.height)));
  };
  for (int i = 0; i <= 5; ++i) {
    const double v = i / 5.0;
    cv::line(img, px(v, 0), px(v, 1), {225, 225, 225}, 1);
    cv::line(img, px(0, v), px(1, v), {225, 225, 225}, 1);
    char buf[16];
    std::snprintf(buf, sizeof buf, "%.1f", v);
    text(img, buf, px(v, 0) + cv::Point(-12, 20), 0.45);
    text(img, buf, px(0, v) + cv::Point(-34, 5), 0.45);
  }
  cv::line(img, px(0, 0), px(1, 1), {120, 120, 120}, 1, cv::LINE_AA);
  text(img, "mean P(occupied) of the bin", cv::Point(box.x + box.width / 2 - 110, box.y + box.height + 42), 0.5);
  plot::verticalLabel(img, "share of the bin's cells truly occupied", cv::Point(area.x + 4, box.y), box.height);
  text(img, plot::scenarioTitle(sc), cv::Point(box.x, area.y + 26), 0.55);
  // OctoMap's curve is rtog's; the end-point model's is far off the diagonal.
  const std::vector<const MapResult*> maps = plot::shownMaps(r, sc, false);
  for (const MapResult* m : maps) {
    const cv::Scalar c = plot::colourOf(m->map);
    std::vector<cv::Point> pts;
    const double cells = std::max<double>(1.0, static_cast<double>(m->metrics.cells));
    for (const auto& b : m->metrics.reliability) {
      if (b.cells == 0) continue;
      const cv::Point p = px(b.mean_p, b.occupied_share);
      pts.push_back(p);
      const int radius = 2 + static_cast<int>(std::lround(10.0 * std::sqrt(static_cast<double>(b.cells) / cells)));
      cv::circle(img, p, radius, c, 1, cv::LINE_AA);
    }
    cv::polylines(img, pts, false, c, 2, cv::LINE_AA);
  }
  cv::rectangle(img, box, {0, 0, 0}, 1);
  for (std::size_t j = 0; j < maps.size(); ++j) {
    char buf[96];
    const std::string name = maps[j]->map == "rtog" ? "rtog = octomap" : maps[j]->map;
    std::snprintf(buf, sizeof buf, "%s  ECE %.3f", name.c_str(), maps[j]->metrics.ece);
    // Bottom right: the over-confident corner, which none of these curves enters.
    const cv::Point lp(box.x + box.width - 392, box.y + box.height - 12 - 22 * static_cast<int>(maps.size() - 1 - j));
    cv::line(img, lp + cv::Point(0, -5), lp + cv::Point(25, -5), plot::colourOf(maps[j]->map), 2, cv::LINE_AA);
    text(img, buf, lp + cv::Point(32, 0), 0.45);
  }
}

}  // namespace

void writeReliabilityPng(const Report& r, std::ostream& os) {
  const int w = 600, h = 560, cols = 2;
  const int n = static_cast<int>(r.scenarios.size());
  const int rows = std::max(1, (n + cols - 1) / cols);
  cv::Mat img(rows * h + 30, cols * w, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int i = 0; i < n; ++i)
    panel(img, cv::Rect((i % cols) * w, 30 + (i / cols) * h, w, h), r, r.scenarios[static_cast<std::size_t>(i)]);
  char title[160];
  std::snprintf(title, sizeof title, "Reliability of P(occupied) vs ground truth - synthetic world seed %u, %.2f m cells, %d bins",
                r.config.seed, r.config.resolution, sim::kCalibrationBins);
  plot::text(img, title, cv::Point(20, 24), 0.6);
  os << image::encodePng(img);
}

}  // namespace rtog::accuracy
