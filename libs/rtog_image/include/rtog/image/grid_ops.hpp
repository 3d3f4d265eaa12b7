// Image operations on the grid (the estimator seed, section 4): a height band as an image of
// probabilities, and threshold, Gaussian blur, morphological open/close, Hough wall segments,
// connected free regions, and polar <-> Cartesian resampling of range scans, through OpenCV.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "rtog/core/occupancy_map.hpp"

namespace rtog::image {

/// A height band as an image: CV_32F P(occupied) per column (the band's highest log-odds, as the
/// 2D view shows it), NaN where no cell is known. Row 0 is the highest y (y up, as MRPT draws
/// grids): pixel (row r, column c) is the column of key (x0 + c, y0 + rows - 1 - r).
struct GridImage {
  cv::Mat p;
  std::int32_t x0 = 0, y0 = 0;
  double resolution = 0.0;
  /// The map coordinates [m] of a pixel's centre (column, row may be fractional).
  Eigen::Vector2d toMetres(double column, double row) const {
    return Eigen::Vector2d((x0 + column + 0.5) * resolution, (y0 + (p.rows - 1 - row) + 0.5) * resolution);
  }
};

/// The map's columns over [zmin, zmax] [m] within its known cells' bounding box. Throws
/// std::invalid_argument for an empty map or zmin > zmax, std::length_error beyond 2^28 pixels.
GridImage bandImage(const OccupancyMap& map, double zmin, double zmax);

/// CV_8UC3 for a picture (picture.hpp): grey 255 (1 - P), unknown light blue, one pixel a cell.
cv::Mat probabilityCells(const GridImage& g);

/// CV_8U: 255 where P >= p (unknown pixels 0).
cv::Mat threshold(const GridImage& g, double p);
/// The image blurred by a Gaussian of sigma [m], unknown pixels left out of the weights
/// (normalized convolution) and unknown again after; throws std::invalid_argument for sigma <= 0.
/// The kernel is clipped to the image (the same weighted means). A sigma over 32 cells runs on
/// blocks of sigma / 16 cells (their means), interpolated back: within about 1e-3 of the exact
/// weighted means, at a cost that does not grow with sigma (a huge one gives nearly the known
/// cells' mean).
GridImage blur(const GridImage& g, double sigma);
/// The blur the estimator seed relates to pose uncertainty: a cell unseen from a pose keeps the
/// prior there, so unknown pixels count as `prior` (P), and the image is first widened by 3 sigma
/// of prior on every side (what poses within 3 sigma see). Every pixel of the result is known.
/// Blurring a scan's view by sigma this way is inserting the scan with isotropic position
/// covariance sigma^2 (tests/mrpt/test_grid_image.cpp). Throws std::invalid_argument for
/// sigma <= 0 or a prior outside (0, 1).
GridImage blurWithPrior(const GridImage& g, double sigma, double prior);
/// Morphological opening / closing of a mask by a k x k square (k odd, >= 1).
cv::Mat open(const cv::Mat& mask, int k);
cv::Mat close(const cv::Mat& mask, int k);

struct Segment {
  Eigen::Vector2d a, b;  ///< end points [m]
  double length() const { return (b - a).norm(); }
};
/// Straight walls of a mask as segments in metres (OpenCV's probabilistic Hough transform: at
/// least min_length long, gaps up to max_gap bridged, 1 pixel and 1 degree bins), longest first.
std::vector<Segment> houghSegments(const cv::Mat& mask, const GridImage& geometry, double min_length, double max_gap);

/// Connected regions (8-connected) of a mask: CV_32S labels, 0 the background; returns the count
/// of regions (background not counted) and each region's area in pixels (index = label).
int connectedRegions(const cv::Mat& mask, cv::Mat& labels, std::vector<int>& areas);

/// A scan's ranges (one per angle, angles from -aperture/2 to +aperture/2 counter-clockwise; a
/// range <= 0 or beyond max_range is no return) as a Cartesian CV_8U image centred on the sensor,
/// `resolution` metres per pixel, x right and y up: 255 at the end points.
cv::Mat polarToCartesian(const std::vector<float>& ranges, double aperture, double max_range, double resolution);
/// The other way: for each of `beams` angles, the range [m] to the first pixel of `image` (as
/// polarToCartesian makes it, sensor at the centre) at or above 128; 0 where none.
std::vector<float> cartesianToPolar(const cv::Mat& image, std::size_t beams, double aperture, double max_range,
                                    double resolution);

}  // namespace rtog::image
