// ROC plot of the accuracy report, drawn with OpenCV.
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
using plot::colourOf;
using plot::text;

struct Range {
  double x0, x1, y0, y1;
};

void panel(cv::Mat& img, cv::Rect area, const Report& r, const Scenario& sc, const Range& rg) {
  const int ml = 80, mr = 20, mt = 40, mb = 50;
  const cv::Rect plot(area.x + ml, area.y + mt, area.width - ml - mr, area.height - mt - mb);
  auto px = [&](double fpr, double tpr) {
    const double u = (fpr - rg.x0) / (rg.x1 - rg.x0), v = (tpr - rg.y0) / (rg.y1 - rg.y0);
    return cv::Point(plot.x + static_cast<int>(std::lround(u * plot.width)),
                     plot.y + plot.height - static_cast<int>(std::lround(v * plot.height)));
  };
  // Grid, ticks and labels.
  for (int i = 0; i <= 5; ++i) {
    const double vx = rg.x0 + (rg.x1 - rg.x0) * i / 5.0, vy = rg.y0 + (rg.y1 - rg.y0) * i / 5.0;
    cv::line(img, px(vx, rg.y0), px(vx, rg.y1), {225, 225, 225}, 1);
    cv::line(img, px(rg.x0, vy), px(rg.x1, vy), {225, 225, 225}, 1);
    char buf[16];
    std::snprintf(buf, sizeof buf, "%.2f", vx);
    text(img, buf, px(vx, rg.y0) + cv::Point(-16, 20), 0.45);
    std::snprintf(buf, sizeof buf, "%.2f", vy);
    text(img, buf, px(rg.x0, vy) + cv::Point(-44, 5), 0.45);
  }
  {  // chance diagonal, clipped
    cv::Point a = px(std::max(rg.x0, rg.y0), std::max(rg.x0, rg.y0)), b = px(std::min(rg.x1, rg.y1), std::min(rg.x1, rg.y1));
    if (cv::clipLine(plot, a, b)) cv::line(img, a, b, {160, 160, 160}, 1, cv::LINE_AA);
  }
  text(img, "false positive rate (free cells called occupied)", cv::Point(plot.x + 20, plot.y + plot.height + 42), 0.5);
  plot::verticalLabel(img, "true positive rate (occupied recall)", cv::Point(area.x + 4, plot.y), plot.height);
  const bool zoom = rg.x1 - rg.x0 < 1.0;
  text(img, plot::scenarioTitle(sc) + (zoom ? " - zoom" : ""), cv::Point(plot.x, area.y + 26), 0.5, {0, 0, 0}, 1);
  // Curves, the first map (rtog) last and thinnest so that it stays visible where another
  // map's curve is the same; then the legend.
  const std::vector<const MapResult*> maps = plot::shownMaps(r, sc, true);
  for (std::size_t j = maps.size(); j-- > 0;) {
    const cv::Scalar c = colourOf(maps[j]->map);
    std::vector<cv::Point> pts;
    for (const auto& p : maps[j]->metrics.roc) pts.push_back(px(p.first, p.second));
    const int thick = j == 0 ? 2 : 5;
    cv::Mat layer = img.clone();
    cv::polylines(layer, pts, false, c, thick, cv::LINE_AA);
    for (const auto& p : pts) cv::circle(layer, p, j == 0 ? 2 : 3, c, cv::FILLED, cv::LINE_AA);
    layer(plot).copyTo(img(plot));
  }
  cv::rectangle(img, plot, {0, 0, 0}, 1);
  for (std::size_t j = 0; j < maps.size(); ++j) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s  AUC %.4f", maps[j]->map.c_str(), maps[j]->metrics.auc);
    const cv::Point lp(plot.x + plot.width - 404, plot.y + plot.height - 14 - 22 * static_cast<int>(maps.size() - 1 - j));
    cv::line(img, lp + cv::Point(0, -5), lp + cv::Point(25, -5), colourOf(maps[j]->map), j == 0 ? 2 : 5, cv::LINE_AA);
    text(img, buf, lp + cv::Point(32, 0), 0.45);
  }
}
}  // namespace

void writeRocPng(const Report& r, std::ostream& os) {
  // Top row: the whole curves; bottom row: the top-left corner where they differ.
  const int w = 600, h = 520;
  const int n = static_cast<int>(r.scenarios.size());
  cv::Mat img(2 * h + 30, std::max(1, n) * w, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int i = 0; i < n; ++i) {
    const Scenario& sc = r.scenarios[static_cast<std::size_t>(i)];
    panel(img, cv::Rect(i * w, 30, w, h), r, sc, Range{0, 1, 0, 1});
    panel(img, cv::Rect(i * w, 30 + h, w, h), r, sc, Range{0, 0.2, 0.6, 1.0});
  }
  char title[160];
  std::snprintf(title, sizeof title, "ROC of P(occupied) vs ground truth - synthetic world seed %u, %.2f m cells",
                r.config.seed, r.config.resolution);
  text(img, title, cv::Point(20, 24), 0.6, {0, 0, 0}, 1);
  os << image::encodePng(img);
}

}  // namespace rtog::accuracy
