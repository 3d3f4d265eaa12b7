#include "rtog/image/grid_ops.hpp"

#include "rtog/core/band.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

namespace rtog::image {

GridImage bandImage(const OccupancyMap& map, double zmin, double zmax) {
  if (!(zmin <= zmax)) throw std::invalid_argument("the band needs zmin <= zmax, got " + std::to_string(zmin) + " and " + std::to_string(zmax));
  const Box kb = map.keyBounds();
  if (kb.isEmpty()) throw std::invalid_argument("the map is empty: there is no band to draw");
  const std::int64_t w = kb.extent(0), h = kb.extent(1);
  if (w * h > (std::int64_t{1} << 28))
    throw std::length_error("an image of " + std::to_string(w) + " x " + std::to_string(h) + " pixels is too large");
  GridImage g;
  g.x0 = kb.min.x, g.y0 = kb.min.y, g.resolution = map.resolution();
  g.p = cv::Mat(static_cast<int>(h), static_cast<int>(w), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  // The band's highest log-odds per column (unknown: NaN), then its probability.
  forEachBandRun(map, bandRegion(map, kb, zmin, zmax), [&](std::int32_t ky, std::int32_t kx0, std::int32_t kx1, const float* run) {
    std::copy(run, run + (kx1 - kx0 + 1), g.p.ptr<float>(static_cast<int>(kb.max.y - ky)) + (kx0 - kb.min.x));
  });
  for (int r = 0; r < g.p.rows; ++r) {
    float* row = g.p.ptr<float>(r);
    for (int c = 0; c < g.p.cols; ++c)
      if (!std::isnan(row[c])) row[c] = static_cast<float>(probability(row[c]));
  }
  return g;
}

cv::Mat probabilityCells(const GridImage& g) {
  cv::Mat img(g.p.size(), CV_8UC3);
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c) {
      const float p = g.p.at<float>(r, c);
      const auto grey = std::isnan(p) ? 0 : static_cast<int>(std::lround(255.0 * (1.0 - p)));
      img.at<cv::Vec3b>(r, c) = std::isnan(p) ? cv::Vec3b(235, 206, 135) : cv::Vec3b(grey, grey, grey);
    }
  return img;
}

cv::Mat threshold(const GridImage& g, double p) {
  cv::Mat m(g.p.size(), CV_8U, cv::Scalar(0));
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c) m.at<std::uint8_t>(r, c) = g.p.at<float>(r, c) >= p ? 255 : 0;  // NaN: 0
  return m;
}

namespace {

/// Gaussian blur of sigma s [pixels] with a zero border, the kernel reaching 3 sigma but no further
/// than across the image: beyond it there is only the zero border, so the weights kept are the
/// whole Gaussian's up to one scale, which cancels in a normalized convolution's num / den.
cv::Mat clippedGaussian(const cv::Mat& m, double s) {
  const double reach = std::ceil(3.0 * s);
  const int kx = 2 * static_cast<int>(std::min(reach, double(m.cols - 1))) + 1;
  const int ky = 2 * static_cast<int>(std::min(reach, double(m.rows - 1))) + 1;
  cv::Mat out;
  cv::GaussianBlur(m, out, cv::Size(kx, ky), s, s, cv::BORDER_CONSTANT);
  return out;
}

/// Above this sigma [pixels] the blur runs on blocks of cells (kPooledSigma / 16 a side, their
/// means), then is interpolated back: the field is smooth at that scale, and the cost is the
/// image's once over plus a kernel of at most 97 taps on the blocks, whatever the sigma.
constexpr double kPooledSigma = 32.0;

/// The blur of `m` at s > kPooledSigma pixels: pooled by f = floor(s / 16) (box means), blurred
/// at s / f, back to the cells by bilinear interpolation (each block's value at its centre).
cv::Mat pooledGaussian(const cv::Mat& m, double s) {
  const int f = static_cast<int>(std::floor(s / 16.0));
  const int sw = (m.cols + f - 1) / f, sh = (m.rows + f - 1) / f;
  cv::Mat padded, small, back;
  cv::copyMakeBorder(m, padded, 0, sh * f - m.rows, 0, sw * f - m.cols, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::resize(padded, small, cv::Size(sw, sh), 0, 0, cv::INTER_AREA);
  cv::resize(clippedGaussian(small, s / f), back, cv::Size(sw * f, sh * f), 0, 0, cv::INTER_LINEAR);
  return back(cv::Rect(0, 0, m.cols, m.rows)).clone();
}

}  // namespace

GridImage blur(const GridImage& g, double sigma) {
  if (!(std::isfinite(sigma) && sigma > 0.0)) throw std::invalid_argument("the blur's sigma must be a positive number of metres");
  const double s = sigma / g.resolution;
  cv::Mat known(g.p.size(), CV_32F), value(g.p.size(), CV_32F);
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c) {
      const float v = g.p.at<float>(r, c);
      known.at<float>(r, c) = std::isnan(v) ? 0.0f : 1.0f;
      value.at<float>(r, c) = std::isnan(v) ? 0.0f : v;
    }
  const bool pooled = s > kPooledSigma;
  const cv::Mat num = pooled ? pooledGaussian(value, s) : clippedGaussian(value, s);
  const cv::Mat den = pooled ? pooledGaussian(known, s) : clippedGaussian(known, s);
  GridImage out = g;
  out.p = g.p.clone();
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c)
      if (!std::isnan(g.p.at<float>(r, c))) out.p.at<float>(r, c) = num.at<float>(r, c) / den.at<float>(r, c);
  return out;
}

GridImage blurWithPrior(const GridImage& g, double sigma, double prior) {
  if (!(std::isfinite(sigma) && sigma > 0.0)) throw std::invalid_argument("the blur's sigma must be a positive number of metres");
  if (!(prior > 0.0 && prior < 1.0)) throw std::invalid_argument("the prior must lie in (0, 1)");
  const double s = sigma / g.resolution;
  const int pad = static_cast<int>(std::ceil(3.0 * s));
  cv::Mat value(g.p.rows + 2 * pad, g.p.cols + 2 * pad, CV_32F, cv::Scalar(prior));
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c) {
      const float v = g.p.at<float>(r, c);
      if (!std::isnan(v)) value.at<float>(r + pad, c + pad) = v;
    }
  GridImage out;
  out.x0 = g.x0 - pad, out.y0 = g.y0 - pad, out.resolution = g.resolution;
  cv::GaussianBlur(value, out.p, cv::Size(2 * pad + 1, 2 * pad + 1), s, s, cv::BORDER_REPLICATE);
  return out;
}

namespace {
cv::Mat morphology(const cv::Mat& mask, int k, int op) {
  if (k < 1 || k % 2 == 0 || k > 1001) throw std::invalid_argument("the structuring element's size must be odd, 1 to 1001, got " + std::to_string(k));
  cv::Mat out;
  cv::morphologyEx(mask, out, op, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  return out;
}
}  // namespace

cv::Mat open(const cv::Mat& mask, int k) { return morphology(mask, k, cv::MORPH_OPEN); }
cv::Mat close(const cv::Mat& mask, int k) { return morphology(mask, k, cv::MORPH_CLOSE); }

std::vector<Segment> houghSegments(const cv::Mat& mask, const GridImage& geo, double min_length, double max_gap) {
  if (!(min_length > 0.0 && max_gap >= 0.0)) throw std::invalid_argument("Hough: need min_length > 0 and max_gap >= 0");
  std::vector<cv::Vec4i> lines;
  const double len_px = min_length / geo.resolution;
  cv::HoughLinesP(mask, lines, 1.0, CV_PI / 180.0, std::max(10, static_cast<int>(len_px / 2)), len_px, max_gap / geo.resolution);
  std::vector<Segment> out;
  for (const auto& l : lines) out.push_back({geo.toMetres(l[0], l[1]), geo.toMetres(l[2], l[3])});
  std::stable_sort(out.begin(), out.end(), [](const Segment& a, const Segment& b) { return a.length() > b.length(); });
  return out;
}

int connectedRegions(const cv::Mat& mask, cv::Mat& labels, std::vector<int>& areas) {
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  areas.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) areas[static_cast<std::size_t>(i)] = stats.at<int>(i, cv::CC_STAT_AREA);
  return n - 1;
}

namespace {
void checkScanGeometry(double aperture, double max_range, double resolution) {
  if (!(aperture > 0.0 && aperture <= 2.0 * M_PI) || !(max_range > 0.0 && std::isfinite(max_range)) ||
      !(resolution > 0.0) || max_range / resolution > 20000.0)
    throw std::invalid_argument("polar/Cartesian: need an aperture in (0, 2 pi], a finite max range > 0 and at most 20000 pixels of range");
}
double beamAngle(std::size_t i, std::size_t n, double aperture) {
  return n < 2 ? 0.0 : -0.5 * aperture + aperture * double(i) / double(n - 1);
}
}  // namespace

cv::Mat polarToCartesian(const std::vector<float>& ranges, double aperture, double max_range, double resolution) {
  checkScanGeometry(aperture, max_range, resolution);
  const int c = static_cast<int>(std::ceil(max_range / resolution));
  cv::Mat img(2 * c + 1, 2 * c + 1, CV_8U, cv::Scalar(0));
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double r = ranges[i];
    if (!(r > 0.0 && r <= max_range)) continue;
    const double a = beamAngle(i, ranges.size(), aperture);
    const int px = c + static_cast<int>(std::lround(r * std::cos(a) / resolution));
    const int py = c - static_cast<int>(std::lround(r * std::sin(a) / resolution));
    img.at<std::uint8_t>(py, px) = 255;
  }
  return img;
}

std::vector<float> cartesianToPolar(const cv::Mat& image, std::size_t beams, double aperture, double max_range,
                                    double resolution) {
  checkScanGeometry(aperture, max_range, resolution);
  if (image.type() != CV_8U || image.rows != image.cols || image.rows % 2 == 0)
    throw std::invalid_argument("polar/Cartesian: need a square single-channel 8-bit image of odd size");
  const int c = image.rows / 2;
  std::vector<float> out(beams, 0.0f);
  for (std::size_t i = 0; i < beams; ++i) {
    const double a = beamAngle(i, beams, aperture);
    for (double r = 0.5 * resolution; r <= max_range + resolution; r += 0.25 * resolution) {
      const int px = c + static_cast<int>(std::lround(r * std::cos(a) / resolution));
      const int py = c - static_cast<int>(std::lround(r * std::sin(a) / resolution));
      if (px < 0 || py < 0 || px >= image.cols || py >= image.rows) break;
      if (image.at<std::uint8_t>(py, px) >= 128) {
        out[i] = static_cast<float>(r);
        break;
      }
    }
  }
  return out;
}

}  // namespace rtog::image
