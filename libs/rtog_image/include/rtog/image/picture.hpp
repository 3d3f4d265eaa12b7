// A map image a person can read without zooming: the cells scaled up, framed by axes with ticks
// in metres (x to the right, y up, as MRPT draws grids, with its axis colours: x red, y green), a
// scale bar and a legend. Every picture the tools write is made here; images that are data (one
// pixel a cell, read back as priors or compared by scripts) are not pictures and stay as they are.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

namespace rtog::image {

struct LegendEntry {
  cv::Vec3b colour;  ///< BGR
  std::string label;
};

struct PictureOptions {
  std::string title;                ///< above the plot (Default: none)
  std::vector<LegendEntry> legend;  ///< swatches beside the plot (Default: none)
  /// A ramp of grey 255 (1 - P) from P = 0 to 1 in the legend, for cells drawn by probability.
  /// (Default: false)
  bool probability_ramp = false;
  std::string ramp_label = "P(occupied)";  ///< the ramp's caption (Default: "P(occupied)")
  /// The cells are scaled by the whole factor (1 to 16) that brings the plot's longer side
  /// nearest this many pixels without going under it, where a factor of 1 does not already pass it.
  /// (Default: 800)
  int target_pixels = 800;
};

class Picture {
 public:
  /// `cells`: CV_8UC3 (BGR) or CV_8UC1, one pixel a cell, row 0 the highest y; its lower-left
  /// cell's lower-left corner lies at (x0, y0) [m]; cells `resolution` [m] wide. Throws
  /// std::invalid_argument for an empty image or a resolution that is not a positive number.
  Picture(const cv::Mat& cells, double x0, double y0, double resolution, PictureOptions options = {});
  /// A picture of rows x cols cells, all `background` (BGR) until paintCell(): for cells that
  /// come one by one (a map's slice), without an image of them beside the canvas.
  Picture(int rows, int cols, const cv::Vec3b& background, double x0, double y0, double resolution,
          PictureOptions options = {});

  /// Paints cell (column, row) `colour` (BGR), as the constructor paints a cell of `cells`.
  void paintCell(int column, int row, const cv::Vec3b& colour) {
    for (int dy = 0; dy < scale_; ++dy) {
      auto* out = canvas_.ptr<cv::Vec3b>(plot_.y + row * scale_ + dy) + plot_.x + column * scale_;
      for (int dx = 0; dx < scale_; ++dx) out[dx] = colour;
    }
  }

  /// The pixel of map point p [m] (overlays: paths, segments).
  cv::Point toPixel(const Eigen::Vector2d& p) const;
  /// The pixels of cell (column, row) of `cells`.
  cv::Rect cellRect(int column, int row) const;
  /// Pixels per cell.
  int scale() const { return scale_; }
  /// Where the scaled cells lie on the canvas.
  const cv::Rect& plotArea() const { return plot_; }
  /// The canvas (BGR): overlays are drawn on it before finish().
  cv::Mat& canvas() { return canvas_; }

  /// Draws the frame, ticks, axes, scale bar and legend over the canvas and returns it.
  const cv::Mat& finish();

  /// Writes the finished picture of `cells` (as the constructor from cells takes them) to `path`
  /// as PNG, a band of rows at a time: neither its canvas nor a second image of the cells is ever
  /// held whole. The pixels are finish()'s for the same cells and options. Throws as the
  /// constructor, and std::runtime_error if the file cannot be written.
  static void writePng(const std::string& path, const cv::Mat& cells, double x0, double y0, double resolution,
                       PictureOptions options = {});

 private:
  struct Layout {};
  /// The geometry alone (no canvas).
  Picture(Layout, int rows, int cols, double x0, double y0, double resolution, PictureOptions options);
  static void checkCells(const cv::Mat& cells);
  /// Canvas row y (in the plot) of the cells, into `row` (the canvas's row y).
  void paintPlotRow(const cv::Mat& cells, int y, cv::Vec3b* row) const;
  /// finish()'s drawing onto `canvas`, whose first row is the canvas's row `top`.
  void decorate(cv::Mat& canvas, int top) const;

  cv::Mat canvas_;
  cv::Size size_;
  cv::Rect plot_;
  int scale_ = 1, rows_ = 0, cols_ = 0;
  double x0_ = 0.0, y0_ = 0.0, res_ = 0.0;
  PictureOptions o_;
};

/// The PNG bytes of an 8-bit grey or BGR image (best compression); throws
/// std::invalid_argument for another image, std::runtime_error if it cannot be encoded.
std::string encodePng(const cv::Mat& image);
/// Writes an 8-bit grey or BGR image to `path` as PNG (zlib's default compression); throws as
/// encodePng, and std::runtime_error if the file cannot be written.
void writePng(const std::string& path, const cv::Mat& image);

}  // namespace rtog::image
