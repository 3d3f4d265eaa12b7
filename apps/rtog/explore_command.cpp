// rtog explore: the frontier regions and the next-best views of a saved map
// (rtog/core/explore.hpp), as JSON and as a picture of the band.
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "rtog/app/output_files.hpp"
#include "rtog/image/grid_ops.hpp"
#include "rtog/image/picture.hpp"

namespace rtog::cli {

namespace {

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

/// The band, the frontier cells (orange), the robot (green) and the best views (red arrows, the
/// best thickest, numbered by rank).
std::string drawExplore(const OccupancyMap& map, const std::vector<FrontierRegion>& regions, const std::vector<View>& views,
                        const ExploreCommandOptions& o) {
  const image::GridImage g = image::bandImage(map, o.views.frontiers.min_z, o.views.frontiers.max_z);
  image::PictureOptions po;
  std::ostringstream title;
  title << regions.size() << " frontier regions, " << views.size() << " views scored";
  po.title = title.str();
  const cv::Vec3b frontier(0, 140, 255), robot(0, 160, 0), view(0, 0, 220);
  po.legend = {{cv::Vec3b(235, 206, 135), "unknown"}, {frontier, "frontier"}, {robot, "robot"}, {view, "views, best first"}};
  po.probability_ramp = true;
  cv::Mat cells = image::probabilityCells(g);
  for (const FrontierRegion& r : regions)
    for (const Box& b : r.boxes)
      for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
        for (std::int32_t x = b.min.x; x <= b.max.x; ++x) {
          const int c = x - g.x0, row = g.p.rows - 1 - (y - g.y0);
          if (c >= 0 && c < g.p.cols && row >= 0 && row < g.p.rows) cells.at<cv::Vec3b>(row, c) = frontier;
        }
  image::Picture pic(cells, g.x0 * g.resolution, g.y0 * g.resolution, g.resolution, po);
  cv::Mat& img = pic.canvas();
  for (std::size_t i = views.size(); i-- > 0;) {
    const View& v = views[i];
    if (!v.reachable) continue;
    const Eigen::Vector2d p = v.pose.translation().head<2>();
    // The sensor's forward axis in the plane (the optical z of a camera).
    const Eigen::Vector3d fwd = v.pose.linear() * (o.views.sensor.kind == ViewSensor::Kind::Depth ? Eigen::Vector3d::UnitZ()
                                                                                                    : Eigen::Vector3d::UnitX());
    const Eigen::Vector2d tip = p + 0.6 * fwd.head<2>().normalized();
    cv::arrowedLine(img, pic.toPixel(p), pic.toPixel(tip), cv::Scalar(view[0], view[1], view[2]), i == 0 ? 3 : 1, cv::LINE_AA,
                    0, 0.35);
    cv::putText(img, std::to_string(i + 1), pic.toPixel(p) + cv::Point(4, -4), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(view[0], view[1], view[2]), 1, cv::LINE_AA);
  }
  cv::circle(img, pic.toPixel(o.from.head<2>()), 6, cv::Scalar(robot[0], robot[1], robot[2]), cv::FILLED);
  return image::encodePng(pic.finish());
}

}  // namespace

int explore(const ExploreCommandOptions& o, std::ostream& out) {
  if (o.out_path.empty()) throw std::invalid_argument("explore: --out FILE.json is required");
  app::OutputSet files({{"map", o.map_path}});
  std::ostream& json_out = files.add("--out", o.out_path);
  std::ostream* png = o.png_path.empty() ? nullptr : &files.add("--png", o.png_path);
  const OccupancyMap map = loadMap(o.map_path);
  ViewOptions vo = o.views;
  vo.frontiers.planar = !o.three_d;
  const std::vector<FrontierRegion> regions = frontierRegions(map, vo.frontiers);
  const std::vector<View> views = nextBestViews(map, regions, o.from, vo);
  nlohmann::json j;
  j["resolution"] = map.resolution();
  j["from"] = vec(o.from);
  j["regions"] = nlohmann::json::array();
  for (const FrontierRegion& r : regions)
    j["regions"].push_back({{"cells", r.cells}, {"centroid", vec(r.centroid)}, {"normal", vec(r.normal)}});
  j["views"] = nlohmann::json::array();
  for (const View& v : views) {
    const Eigen::Quaterniond q(v.pose.linear());
    j["views"].push_back({{"position", vec(v.pose.translation())},
                          {"orientation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
                          {"region", v.region},
                          {"gain_bits", v.gain.bits},
                          {"cells_seen", v.gain.cells},
                          {"unknown_cells_seen", v.gain.unknown_cells},
                          {"reachable", v.reachable},
                          {"path_cost", v.path_cost},
                          {"path_length", v.path_length},
                          {"score", v.score}});
  }
  json_out << j.dump(1) << "\n";
  if (png) *png << drawExplore(map, regions, views, o);
  files.commit();
  out << regions.size() << " frontier regions (" << (o.three_d ? "3D" : "band") << "), " << views.size()
      << " views scored";
  if (!views.empty() && views.front().reachable)
    out << "; best: (" << std::fixed << std::setprecision(2) << views.front().pose.translation().x() << ", "
        << views.front().pose.translation().y() << "), " << std::setprecision(1) << views.front().gain.bits << " bits, path "
        << std::setprecision(2) << views.front().path_length << " m";
  out << "\n";
  return 0;
}

}  // namespace rtog::cli
