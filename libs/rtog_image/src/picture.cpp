#include "rtog/image/picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "png_rows.hpp"

namespace rtog::image {
namespace {

constexpr int kLeft = 76, kBottom = 54, kTop = 40, kGap = 24, kPanel = 210;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kText = 0.45;
const cv::Scalar kInk(40, 40, 40), kRed(30, 30, 220), kGreen(40, 160, 40), kWhite(255, 255, 255);

/// 1, 2 or 5 times a power of ten, the nearest at or above `raw`.
double niceStep(double raw) {
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw * 0.999) return m * p;
  return 10.0 * p;
}

/// "12", "2.5", "0.025": at most three decimals, no trailing zeros.
std::string metres(double v) {
  if (std::fabs(v) < 1e-9) v = 0.0;
  char s[32];
  std::snprintf(s, sizeof s, "%.3f", v);
  std::string t(s);
  while (!t.empty() && t.back() == '0') t.pop_back();
  if (!t.empty() && t.back() == '.') t.pop_back();
  return t;
}

cv::Size textSize(const std::string& s) {
  int base = 0;
  return cv::getTextSize(s, kFont, kText, 1, &base);
}

/// Draws on the canvas, or on a band of it whose first row is canvas row `top`: the points and
/// rectangles given are the canvas's.
struct Pen {
  cv::Mat& img;
  int top;
  cv::Point at(cv::Point p) const { return {p.x, p.y - top}; }
  void line(cv::Point a, cv::Point b, const cv::Scalar& colour, int thickness) {
    cv::line(img, at(a), at(b), colour, thickness);
  }
  void rectangle(const cv::Rect& r, const cv::Scalar& colour, int thickness) {
    cv::rectangle(img, cv::Rect(r.x, r.y - top, r.width, r.height), colour, thickness);
  }
  void arrow(cv::Point from, cv::Point to, const cv::Scalar& colour) {
    cv::arrowedLine(img, at(from), at(to), colour, 2, cv::LINE_AA, 0, 0.2);
  }
  void text(const std::string& s, cv::Point p, const cv::Scalar& colour = kInk) {
    cv::putText(img, s, at(p), kFont, kText, colour, 1, cv::LINE_AA);
  }
};

/// MRPT's axes: x red to the right, y green up, from `o`, `len` pixels long.
void axes(Pen& img, cv::Point o, int len) {
  img.arrow(o, o + cv::Point(len, 0), kRed);
  img.arrow(o, o + cv::Point(0, -len), kGreen);
  img.text("x", o + cv::Point(len + 4, 5), kRed);
  img.text("y", o + cv::Point(-4, -len - 6), kGreen);
}

}  // namespace

Picture::Picture(Layout, int rows, int cols, double x0, double y0, double resolution, PictureOptions options)
    : rows_(rows), cols_(cols), x0_(x0), y0_(y0), res_(resolution), o_(std::move(options)) {
  if (rows <= 0 || cols <= 0) throw std::invalid_argument("picture: the image has no cells");
  if (!(std::isfinite(resolution) && resolution > 0.0)) throw std::invalid_argument("picture: bad resolution");
  const int side = std::max(rows_, cols_);
  scale_ = std::clamp((std::max(1, o_.target_pixels) + side - 1) / side, 1, 16);
  plot_ = cv::Rect(kLeft, kTop, cols_ * scale_, rows_ * scale_);
  const int legend_h = 40 + 24 * int(o_.legend.size()) + (o_.probability_ramp ? 64 : 0) + 150;
  size_ = cv::Size(kLeft + plot_.width + kGap + kPanel, kTop + std::max(plot_.height, legend_h) + kBottom);
}

Picture::Picture(int rows, int cols, const cv::Vec3b& background, double x0, double y0, double resolution,
                 PictureOptions options)
    : Picture(Layout{}, rows, cols, x0, y0, resolution, std::move(options)) {
  canvas_ = cv::Mat(size_, CV_8UC3, kWhite);
  canvas_(plot_).setTo(cv::Scalar(background[0], background[1], background[2]));
}

Picture::Picture(const cv::Mat& cells, double x0, double y0, double resolution, PictureOptions options)
    : Picture(Layout{}, std::max(cells.rows, 1), std::max(cells.cols, 1), x0, y0, resolution, std::move(options)) {
  checkCells(cells);
  canvas_ = cv::Mat(size_, CV_8UC3, kWhite);
  for (int y = plot_.y; y < plot_.br().y; ++y) paintPlotRow(cells, y, canvas_.ptr<cv::Vec3b>(y));
}

void Picture::checkCells(const cv::Mat& cells) {
  if (cells.empty()) throw std::invalid_argument("picture: the image has no cells");
  if (cells.type() != CV_8UC1 && cells.type() != CV_8UC3)
    throw std::invalid_argument("picture: cells must be 8-bit grey or colour");
}

// Grey cells are painted straight into the canvas: a colour copy of them would be a third image
// beside the cells and the canvas.
void Picture::paintPlotRow(const cv::Mat& cells, int y, cv::Vec3b* row) const {
  const int r = (y - plot_.y) / scale_;
  cv::Vec3b* out = row + plot_.x;
  if (cells.type() == CV_8UC1) {
    const std::uint8_t* in = cells.ptr<std::uint8_t>(r);
    for (int c = 0; c < cols_; ++c)
      for (int dx = 0; dx < scale_; ++dx) *out++ = cv::Vec3b(in[c], in[c], in[c]);
  } else {
    const cv::Vec3b* in = cells.ptr<cv::Vec3b>(r);
    for (int c = 0; c < cols_; ++c)
      for (int dx = 0; dx < scale_; ++dx) *out++ = in[c];
  }
}

void Picture::writePng(const std::string& path, const cv::Mat& cells, double x0, double y0, double resolution,
                       PictureOptions options) {
  const Picture p(Layout{}, std::max(cells.rows, 1), std::max(cells.cols, 1), x0, y0, resolution, std::move(options));
  checkCells(cells);
  PngRows png(path, p.size_.width, p.size_.height);
  // Each band drawn with a margin of rows above and below that is not written: what OpenCV
  // draws across a band's edge is clipped there, and may land a pixel off where it would on
  // the whole canvas.
  constexpr int kBand = 64, kMargin = 32;
  cv::Mat band;
  for (int y = 0; y < p.size_.height; y += kBand) {
    const int top = std::max(0, y - kMargin), end = std::min(p.size_.height, y + kBand);
    band.create(std::min(p.size_.height, end + kMargin) - top, p.size_.width, CV_8UC3);
    band.setTo(kWhite);
    for (int r = std::max(top, p.plot_.y); r < std::min(top + band.rows, p.plot_.br().y); ++r)
      p.paintPlotRow(cells, r, band.ptr<cv::Vec3b>(r - top));
    p.decorate(band, top);
    for (int r = y; r < end; ++r) png.write(band.ptr<std::uint8_t>(r - top));
  }
  png.close();
}

cv::Point Picture::toPixel(const Eigen::Vector2d& p) const {
  const double cx = (p.x() - x0_) / res_, cy = (p.y() - y0_) / res_;
  return cv::Point(plot_.x + static_cast<int>(std::floor(cx * scale_)),
                   plot_.y + static_cast<int>(std::floor((rows_ - cy) * scale_)));
}

cv::Rect Picture::cellRect(int column, int row) const {
  return cv::Rect(plot_.x + column * scale_, plot_.y + row * scale_, scale_, scale_);
}

const cv::Mat& Picture::finish() {
  decorate(canvas_, 0);
  return canvas_;
}

void Picture::decorate(cv::Mat& canvas, int top) const {
  Pen img{canvas, top};
  img.rectangle(plot_, kInk, 1);
  // Ticks every 1, 2 or 5 x 10^k m, some six along the longer side, the same step on both axes.
  const double w_m = cols_ * res_, h_m = rows_ * res_;
  const double step = niceStep(std::max(w_m, h_m) / 6.0);
  for (double x = std::ceil(x0_ / step) * step; x <= x0_ + w_m + 1e-9; x += step) {
    const int px = toPixel({x, y0_}).x;
    img.line({px, plot_.br().y}, {px, plot_.br().y + 5}, kInk, 1);
    const std::string s = metres(x);
    img.text(s, {px - textSize(s).width / 2, plot_.br().y + 20});
  }
  for (double y = std::ceil(y0_ / step) * step; y <= y0_ + h_m + 1e-9; y += step) {
    const int py = toPixel({x0_, y}).y;
    img.line({plot_.x - 5, py}, {plot_.x, py}, kInk, 1);
    const std::string s = metres(y);
    img.text(s, {plot_.x - 9 - textSize(s).width, py + 5});
  }
  img.text("x [m]", {plot_.x + plot_.width / 2 - 18, plot_.br().y + 42}, kRed);
  img.text("y [m]", {4, plot_.y - 10}, kGreen);
  if (!o_.title.empty()) img.text(o_.title, {plot_.x + 40, plot_.y - 14});
  // The map's origin, where the plot holds it.
  const cv::Point origin = toPixel({0.0, 0.0});
  if (plot_.contains(origin)) axes(img, origin, std::clamp(plot_.width / 12, 24, 60));
  // Scale bar, bottom right inside the plot, on a white ground.
  const double bar_m = niceStep(w_m / 5.0) / (niceStep(w_m / 5.0) > w_m / 3.0 ? 2.0 : 1.0);
  const int bar = static_cast<int>(std::lround(bar_m / res_ * scale_));
  const std::string label = metres(bar_m) + " m";
  const cv::Point b1(plot_.br().x - 14, plot_.br().y - 14), b0(b1.x - bar, b1.y);
  const int box_w = std::max(bar, textSize(label).width) + 12;
  img.rectangle(cv::Rect(b1.x - box_w + 6, b1.y - 30, box_w, 38), kWhite, cv::FILLED);
  img.rectangle(cv::Rect(b1.x - box_w + 6, b1.y - 30, box_w, 38), kInk, 1);
  img.line(b0, b1, cv::Scalar(0, 0, 0), 4);
  img.line(b0 + cv::Point(0, -6), b0 + cv::Point(0, 4), cv::Scalar(0, 0, 0), 2);
  img.line(b1 + cv::Point(0, -6), b1 + cv::Point(0, 4), cv::Scalar(0, 0, 0), 2);
  img.text(label, {b1.x - bar / 2 - textSize(label).width / 2, b1.y - 12});
  // Legend: swatches, the probability ramp, the cell size, MRPT's axes.
  int x = plot_.br().x + kGap, y = plot_.y + 14;
  for (const auto& e : o_.legend) {
    img.rectangle(cv::Rect(x, y - 12, 16, 16), cv::Scalar(e.colour[0], e.colour[1], e.colour[2]), cv::FILLED);
    img.rectangle(cv::Rect(x, y - 12, 16, 16), kInk, 1);
    img.text(e.label, {x + 24, y + 1});
    y += 24;
  }
  if (o_.probability_ramp) {
    img.text(o_.ramp_label, {x, y + 4});
    const int rw = 150;
    for (int i = 0; i < rw; ++i) {
      const double p = double(i) / (rw - 1);
      const auto g = static_cast<int>(std::lround(255.0 * (1.0 - p)));
      img.line({x + i, y + 12}, {x + i, y + 28}, cv::Scalar(g, g, g), 1);
    }
    img.rectangle(cv::Rect(x, y + 12, rw, 17), kInk, 1);
    img.text("0", {x - 3, y + 46});
    img.text("0.5", {x + rw / 2 - 12, y + 46});
    img.text("1", {x + rw - 5, y + 46});
    y += 64;
  }
  img.text("cell " + metres(res_) + " m", {x, y + 8});
  img.text(std::to_string(scale_) + " px a cell", {x, y + 28});
  axes(img, {x + 10, y + 110}, 50);
}

}  // namespace rtog::image
