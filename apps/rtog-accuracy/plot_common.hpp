// What the two plots of the accuracy report share: a colour per map, text, panel titles.
#pragma once

#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "accuracy.hpp"

namespace rtog::accuracy::plot {

inline cv::Scalar colourOf(const std::string& map) {  // BGR
  if (map == "rtog") return {40, 40, 220};                       // red
  if (map == "rtog_pose_blur") return {20, 20, 120};             // dark red
  if (map == "octomap") return {200, 110, 20};                   // blue
  if (map == "rtog_range_noise") return {180, 40, 180};          // magenta
  if (map == "rtog_range_noise_pose_blur") return {90, 0, 90};   // dark magenta
  if (map == "rtog_endpoint") return {0, 150, 250};              // orange
  if (map == "rtog_endpoint_pose_blur") return {0, 90, 160};     // brown
  if (map == "rtog_calibrated") return {160, 160, 0};             // teal
  if (map == "rtog_range_noise_calibrated") return {0, 0, 0};     // black
  if (map == "rtog_range_noise_pose_blur_calibrated") return {0, 0, 0};
  return {40, 160, 40};                                          // MRPT grids: green
}

/// The maps a plot of scenario `sc` draws, in the report's order: the beam model, MRPT's grid
/// and, of the richest model of the scenario, the map with OctoMap's clamps and the calibrated
/// one; with `all_baselines`, OctoMap and the end-point model too. The JSON has every map.
inline std::vector<const MapResult*> shownMaps(const Report& r, const Scenario& sc, bool all_baselines) {
  const std::string best = sc.pose_noise ? "rtog_range_noise_pose_blur" : "rtog_range_noise";
  std::vector<const MapResult*> maps;
  for (const MapResult& m : r.results) {
    if (m.scenario != sc.name) continue;
    const bool base = m.map == "rtog" || m.map.rfind("mrpt", 0) == 0 || m.map == best || m.map == best + "_calibrated";
    if (base || (all_baselines && (m.map == "octomap" || m.map == "rtog_endpoint"))) maps.push_back(&m);
  }
  return maps;
}

inline void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.5, cv::Scalar c = {0, 0, 0},
                 int thick = 1) {
  cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, thick, cv::LINE_AA);
}

inline std::string scenarioTitle(const Scenario& sc) {
  std::string t = sc.planar ? "2D scanner, scan-plane layer" : "3D LiDAR";
  t += " (" + std::to_string(sc.scans) + " scans";
  if (sc.pose_noise) t += ", noisy poses";
  return t + ")";
}

/// A vertical axis label: drawn horizontally into a strip and rotated, at `at` (top left).
inline void verticalLabel(cv::Mat& img, const std::string& s, cv::Point at, int length) {
  cv::Mat lab(24, length, CV_8UC3, cv::Scalar(255, 255, 255));
  int base = 0;
  const cv::Size size = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, 0.5, 1, &base);
  text(lab, s, cv::Point((length - size.width) / 2, 17), 0.5);
  cv::Mat rot;
  cv::rotate(lab, rot, cv::ROTATE_90_COUNTERCLOCKWISE);
  rot.copyTo(img(cv::Rect(at.x, at.y, rot.cols, rot.rows)));
}

}  // namespace rtog::accuracy::plot
