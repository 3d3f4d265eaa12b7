// rtog plan: a risk-aware path on a saved map (rtog/core/plan.hpp), as text and as a picture.
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/image/picture.hpp"

namespace rtog::cli {

namespace {

/// The planning grid around the path (4 m of margin) as a picture (rtog/image/picture.hpp):
/// grey 255 (1 - T(C)) for known cells, light blue unknown, pink the free cells the radius keeps
/// off, the path in blue from a green start to a red goal.
cv::Mat drawPlan(const PlanGrid& g, const PlanResult& r, const PlanCommandOptions& o) {
  const auto cell = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2i(static_cast<int>(std::floor(p.x() / g.resolution)) - g.x0,
                           static_cast<int>(std::floor(p.y() / g.resolution)) - g.y0);
  };
  Eigen::Vector2i lo(g.nx, g.ny), hi(0, 0);
  for (const auto& p : r.path) lo = lo.cwiseMin(cell(p)), hi = hi.cwiseMax(cell(p));
  const int margin = static_cast<int>(std::ceil(4.0 / g.resolution));
  lo = (lo - Eigen::Vector2i::Constant(margin)).cwiseMax(Eigen::Vector2i::Zero());
  hi = (hi + Eigen::Vector2i::Constant(margin)).cwiseMin(Eigen::Vector2i(g.nx - 1, g.ny - 1));
  const int w = hi.x() - lo.x() + 1, h = hi.y() - lo.y() + 1;
  const cv::Vec3b unknown(235, 206, 135), kept_off(190, 190, 255);
  cv::Mat cells(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = g.index(lo.x() + x, lo.y() + y);
      cv::Vec3b& px = cells.at<cv::Vec3b>(h - 1 - y, x);
      const auto grey = static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - g.risk[i])));
      if (!g.known[i]) px = unknown;
      else if (g.blocked[i] && g.risk[i] < 0.5f) px = kept_off;
      else px = cv::Vec3b(grey, grey, grey);
    }
  image::PictureOptions po;
  std::ostringstream title;
  title << "path: Te " << o.plan.te << ", Ta " << o.plan.ta << "; " << std::setprecision(3) << r.length << " m, risk "
        << r.risk;
  po.title = title.str();
  po.legend = {{unknown, "unknown"}, {kept_off, "within the radius"}, {cv::Vec3b(200, 60, 0), "path"},
               {cv::Vec3b(0, 160, 0), "start"}, {cv::Vec3b(0, 0, 220), "goal"}};
  po.probability_ramp = true;
  po.ramp_label = "T(C) = P(occupied)";
  image::Picture pic(cells, (g.x0 + lo.x()) * g.resolution, (g.y0 + lo.y()) * g.resolution, g.resolution, po);
  cv::Mat& img = pic.canvas();
  for (std::size_t i = 1; i < r.path.size(); ++i)
    cv::line(img, pic.toPixel(r.path[i - 1]), pic.toPixel(r.path[i]), cv::Scalar(200, 60, 0), 2, cv::LINE_AA);
  if (!r.path.empty()) {
    cv::circle(img, pic.toPixel(r.path.front()), 6, cv::Scalar(0, 160, 0), cv::FILLED);
    cv::circle(img, pic.toPixel(r.path.back()), 6, cv::Scalar(0, 0, 220), cv::FILLED);
  }
  return pic.finish().clone();
}

}  // namespace

int plan(const PlanCommandOptions& o, std::ostream& out) {
  if (o.out_path.empty()) throw std::invalid_argument("plan: --out FILE is required (where the path goes)");
  app::OutputSet files({{"map", o.map_path}});
  std::ostream& dst = files.add("--out", o.out_path);
  std::ostream* png = o.png_path.empty() ? nullptr : &files.add("--png", o.png_path);
  const OccupancyMap map = loadMap(o.map_path);
  PlanResult r;                  // the 2D plan, or the 3D one seen from above (for the picture)
  std::size_t nodes = 0, rects = 0;
  std::vector<Eigen::Vector3d> path3;
  if (o.three_d) {
    const PlanResult3D r3 = planPath3D(map, o.from, o.to, o.plan);
    if (!r3.found) throw std::runtime_error("plan: no path from the start to the goal (every way is blocked)");
    path3 = r3.path;
    r.found = true, r.length = r3.length, r.risk = r3.risk, r.cost = r3.cost, r.expanded = r3.expanded, nodes = r3.nodes;
    for (const auto& p : r3.path) r.path.emplace_back(p.x(), p.y());
  }
  const Eigen::Vector2d from2 = o.from.head<2>(), to2 = o.to.head<2>();
  PlanGrid g;
  if (!o.three_d || png) {
    PlanOptions view = o.plan;
    if (o.three_d) view.radius = 0.0, view.cross_free_cuboids = false;  // the background only: every column
    g = buildPlanGrid(map, from2, to2, view);
  }
  if (!o.three_d) {
    r = planOnGrid(g, from2, to2, o.plan);
    if (!r.found) throw std::runtime_error("plan: no path from the start to the goal (every way is blocked)");
    nodes = g.risk.size(), rects = g.rects.size();
  }
  dst << "# " << (o.three_d ? "x y z" : "x y") << " [m], cell centres from start to goal; length " << r.length
      << " m, risk " << r.risk << ", cost " << r.cost << "\n"
      << std::setprecision(10);
  if (o.three_d)
    for (const auto& p : path3) dst << p.x() << " " << p.y() << " " << p.z() << "\n";
  else
    for (const auto& p : r.path) dst << p.x() << " " << p.y() << "\n";
  if (png) *png << image::encodePng(drawPlan(g, r, o));
  files.commit();
  out << (o.three_d ? "3D path of " : "path of ") << r.path.size() << " cells, " << r.length << " m, summed risk "
      << r.risk << ", cost " << r.cost << " (Te " << o.plan.te << ", Ta " << o.plan.ta << "; " << r.expanded
      << " nodes expanded of " << nodes;
  if (!o.three_d) out << ", " << rects << " free cuboids crossed whole";
  out << ")\nwrote " << o.out_path << (png ? " and " + o.png_path : std::string()) << "\n";
  return 0;
}

}  // namespace rtog::cli
