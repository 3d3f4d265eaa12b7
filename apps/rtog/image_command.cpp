// rtog image: image operations on a map's height band (rtog/image/grid_ops.hpp), as JSON and PNG.
#include <cmath>
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

int imageOps(const ImageOptions& o, std::ostream& out) {
  if (o.out_path.empty()) throw std::invalid_argument("image: --out FILE.json is required");
  if (!(o.threshold > 0.0 && o.threshold < 1.0)) throw std::invalid_argument("image: --threshold must lie in (0, 1)");
  app::OutputSet files({{"map", o.map_path}});
  std::ostream& json_out = files.add("--out", o.out_path);
  std::ostream* png = o.png_path.empty() ? nullptr : &files.add("--png", o.png_path);
  std::ostream* prior = o.prior_png_path.empty() ? nullptr : &files.add("--prior-png", o.prior_png_path);
  const OccupancyMap map = loadMap(o.map_path);
  image::GridImage g = image::bandImage(map, o.zmin, o.zmax);
  if (o.blur_sigma > 0.0) g = image::blur(g, o.blur_sigma);
  cv::Mat occupied = image::threshold(g, o.threshold);
  if (o.open_k > 0) occupied = image::open(occupied, o.open_k);
  if (o.close_k > 0) occupied = image::close(occupied, o.close_k);
  nlohmann::json j;
  j["resolution"] = g.resolution;
  j["origin"] = {g.x0 * g.resolution, g.y0 * g.resolution};
  j["size"] = {g.p.cols, g.p.rows};
  j["threshold"] = o.threshold;
  j["occupied_cells"] = cv::countNonZero(occupied);
  std::vector<image::Segment> segments;
  if (o.hough) {
    segments = image::houghSegments(occupied, g, o.hough_min_length, o.hough_max_gap);
    j["segments"] = nlohmann::json::array();
    for (const auto& s : segments) j["segments"].push_back({s.a.x(), s.a.y(), s.b.x(), s.b.y()});
  }
  cv::Mat labels;
  std::vector<int> areas;
  if (o.segment) {
    // Free space: known and below the threshold, the walls closed first so that doors split rooms.
    cv::Mat free(g.p.size(), CV_8U, cv::Scalar(0));
    for (int r = 0; r < g.p.rows; ++r)
      for (int c = 0; c < g.p.cols; ++c)
        free.at<std::uint8_t>(r, c) = g.p.at<float>(r, c) < o.threshold && !occupied.at<std::uint8_t>(r, c) ? 255 : 0;
    const int n = image::connectedRegions(free, labels, areas);
    j["regions"] = nlohmann::json::array();
    for (int i = 1; i <= n; ++i) j["regions"].push_back({{"label", i}, {"area_m2", areas[std::size_t(i)] * g.resolution * g.resolution}});
  }
  json_out << j.dump(1) << "\n";
  if (png) {
    image::PictureOptions po;
    std::ostringstream title;
    title << "band z in [" << o.zmin << ", " << o.zmax << "] m";
    po.title = title.str();
    po.legend = {{cv::Vec3b(235, 206, 135), "unknown"}};
    if (o.hough) po.legend.push_back({cv::Vec3b(0, 0, 230), "Hough walls"});
    if (o.segment) po.legend.push_back({cv::Vec3b(120, 180, 90), "free regions (tinted)"});
    po.probability_ramp = true;
    image::Picture pic(image::probabilityCells(g), g.x0 * g.resolution, g.y0 * g.resolution, g.resolution, po);
    cv::Mat& img = pic.canvas();
    if (o.segment)
      for (int r = 0; r < labels.rows; ++r)
        for (int c = 0; c < labels.cols; ++c) {
          const int l = labels.at<int>(r, c);
          if (l <= 0 || areas[std::size_t(l)] < 100) continue;  // tint the regions of 100 cells and more
          const cv::Vec3b tint((l * 67) % 200 + 55, (l * 131) % 200 + 55, (l * 29) % 200 + 55);
          const cv::Rect cell = pic.cellRect(c, r);
          cv::Mat roi = img(cell);
          roi = 0.5 * roi + 0.5 * cv::Mat(cell.size(), CV_8UC3, cv::Scalar(tint[0], tint[1], tint[2]));
        }
    for (const auto& s : segments) cv::line(img, pic.toPixel(s.a), pic.toPixel(s.b), cv::Scalar(0, 0, 230), 2, cv::LINE_AA);
    *png << image::encodePng(pic.finish());
  }
  if (prior) {
    // One pixel a cell, white free, black occupied, mid-grey unknown: `rtog prior --image` reads it.
    cv::Mat grey(g.p.size(), CV_8U);
    for (int r = 0; r < g.p.rows; ++r)
      for (int c = 0; c < g.p.cols; ++c) {
        const float p = g.p.at<float>(r, c);
        grey.at<std::uint8_t>(r, c) = std::isnan(p) ? 128 : static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - p)));
      }
    *prior << image::encodePng(grey);
  }
  files.commit();
  out << "band " << g.p.cols << " x " << g.p.rows << " cells at " << g.resolution << " m: " << cv::countNonZero(occupied)
      << " occupied";
  if (o.hough) out << ", " << segments.size() << " wall segments";
  if (o.segment) out << ", " << areas.size() - 1 << " free regions";
  out << "\nwrote " << o.out_path << "\n";
  if (prior) out << "the prior image's lower-left corner: --origin " << g.x0 * g.resolution << " " << g.y0 * g.resolution
                 << " --resolution " << g.resolution << "\n";
  return 0;
}

}  // namespace rtog::cli
