// Image operations on the grid (rtog/image/grid_ops.hpp) on SENA's loop: the Hough walls of rtog's
// map (the octomap preset: not the stock grid's update) are the corridor's long walls that the
// stock COccupancyGridMap2D of the same log shows; free regions, blur and polar <-> Cartesian
// resampling of a real scan.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include <mrpt/obs/CObservation2DRangeScan.h>

#include <opencv2/core.hpp>

#include "rtog/core/pose_blur.hpp"
#include "rtog/image/grid_ops.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;
using rtog::image::GridImage;
using rtog::image::Segment;

namespace {

/// The stock grid as a GridImage: P(occupied) = 1 - P(free), NaN where the cell was never observed.
GridImage fromStockGrid(const mrpt::maps::COccupancyGridMap2D& g) {
  GridImage out;
  out.resolution = g.getResolution();
  out.x0 = static_cast<std::int32_t>(std::lround(g.getXMin() / g.getResolution()));
  out.y0 = static_cast<std::int32_t>(std::lround(g.getYMin() / g.getResolution()));
  const int w = static_cast<int>(g.getSizeX()), h = static_cast<int>(g.getSizeY());
  out.p = cv::Mat(h, w, CV_32F);
  for (int cy = 0; cy < h; ++cy)
    for (int cx = 0; cx < w; ++cx)
      out.p.at<float>(h - 1 - cy, cx) = g.getRawMap()[std::size_t(cy) * w + cx] == 0
                                            ? std::numeric_limits<float>::quiet_NaN()
                                            : 1.0f - g.getCell(cx, cy);
  return out;
}

std::vector<Segment> walls(const GridImage& g) {
  return rtog::image::houghSegments(rtog::image::close(rtog::image::threshold(g, 0.5), 3), g, 2.0, 0.3);
}

/// Whether `s` lies along `t`: within 3 degrees, its midpoint within 0.25 m of t's line and
/// within t's extent (plus 0.5 m).
bool along(const Segment& s, const Segment& t) {
  const Eigen::Vector2d ds = (s.b - s.a).normalized(), dt = (t.b - t.a).normalized();
  const double angle = std::acos(std::min(1.0, std::fabs(ds.dot(dt)))) * 180.0 / M_PI;
  const Eigen::Vector2d mid = 0.5 * (s.a + s.b);
  const double along_t = (mid - t.a).dot(dt), off = std::fabs((mid - t.a).x() * dt.y() - (mid - t.a).y() * dt.x());
  return angle < 3.0 && off < 0.25 && along_t > -0.5 && along_t < t.length() + 0.5;
}

}  // namespace

TEST(GridImage, HoughWallsAreTheStockGridsLongWalls) {
  const auto frames = loadOdometryFrames(dataset(kSena));
  auto ours = mapFromIni("sensorModelPreset=octomap\n");
  mrpt::maps::COccupancyGridMap2D stock(-10, 10, -10, 10, 0.05f);
  for (const auto& f : frames)
    for (const auto& obs : *f.sf) ours->insertObservation(*obs, f.pose), stock.insertObservation(*obs, f.pose);
  const auto mine = walls(rtog::image::bandImage(ours->map(), -1000, 1000));
  const auto theirs = walls(fromStockGrid(stock));
  ASSERT_GE(theirs.size(), 6u);
  ASSERT_FALSE(mine.empty());
  std::printf("SENA Hough walls: rtog %zu segments (longest %.2f m), stock grid %zu (longest %.2f m)\n", mine.size(),
              mine.front().length(), theirs.size(), theirs.front().length());
  // The stock grid's six longest walls are corridor walls, and rtog's map has each of them.
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_GT(theirs[i].length(), 4.0) << i;
    bool found = false;
    for (const auto& s : mine) found = found || along(theirs[i], s) || along(s, theirs[i]);
    EXPECT_TRUE(found) << "stock wall " << i << " (" << theirs[i].a.transpose() << ") - (" << theirs[i].b.transpose()
                       << "), " << theirs[i].length() << " m";
  }
}

TEST(GridImage, FreeRegionsBlurAndThresholdOnSena) {
  const auto frames = loadOdometryFrames(dataset(kSena));
  auto m = mapFromIni("");
  for (std::size_t i = 0; i < frames.size(); i += 2)
    for (const auto& obs : *frames[i].sf) m->insertObservation(*obs, frames[i].pose);
  const GridImage g = rtog::image::bandImage(m->map(), -1000, 1000);
  // Free space, the walls closed: one region holds the loop's corridor, far larger than the rest.
  const cv::Mat occ = rtog::image::close(rtog::image::threshold(g, 0.5), 3);
  cv::Mat free(g.p.size(), CV_8U, cv::Scalar(0));
  std::size_t known = 0;
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c) {
      const float p = g.p.at<float>(r, c);
      known += !std::isnan(p);
      free.at<std::uint8_t>(r, c) = p < 0.5f && !occ.at<std::uint8_t>(r, c) ? 255 : 0;
    }
  cv::Mat labels;
  std::vector<int> areas;
  const int n = rtog::image::connectedRegions(free, labels, areas);
  ASSERT_GT(n, 0);
  const int largest = *std::max_element(areas.begin() + 1, areas.end());
  std::printf("SENA free regions: %d, the largest %.1f m^2 of %.1f m^2 known\n", n, largest * 0.0025, known * 0.0025);
  EXPECT_GT(largest, 0.5 * cv::countNonZero(free));
  // Blur keeps the known cells known and the others unknown, and each known cell is the
  // Gaussian-weighted mean of the known cells within 3 sigma (rounded up to whole cells) about
  // it: computed here directly, in doubles, at every known cell, for sigma = 0.1 m (2 cells) and
  // 0.07 m (1.4 cells).
  for (const double sigma : {0.1, 0.07}) {
    const GridImage b = rtog::image::blur(g, sigma);
    ASSERT_EQ(b.p.size(), g.p.size());
    ASSERT_EQ(b.x0, g.x0);
    ASSERT_EQ(b.y0, g.y0);
    const double s = sigma / g.resolution;
    const int radius = static_cast<int>(std::ceil(3.0 * s));
    double worst = 0, moved = 0;
    std::size_t compared = 0;
    for (int r = 0; r < g.p.rows; ++r)
      for (int c = 0; c < g.p.cols; ++c) {
        const float p = g.p.at<float>(r, c), q = b.p.at<float>(r, c);
        ASSERT_EQ(std::isnan(p), std::isnan(q)) << r << ", " << c;
        if (std::isnan(p)) continue;
        double num = 0, den = 0;
        for (int dr = -radius; dr <= radius; ++dr)
          for (int dc = -radius; dc <= radius; ++dc) {
            const int rr = r + dr, cc = c + dc;
            if (rr < 0 || cc < 0 || rr >= g.p.rows || cc >= g.p.cols || std::isnan(g.p.at<float>(rr, cc))) continue;
            const double w = std::exp(-(dr * dr + dc * dc) / (2.0 * s * s));
            num += w * g.p.at<float>(rr, cc), den += w;
          }
        worst = std::max(worst, std::fabs(q - num / den));
        moved = std::max(moved, double(std::fabs(q - p)));
        ++compared;
      }
    std::printf("blur sigma %.2f m: %zu known cells, largest difference from the direct convolution %.2g, largest change "
                "%.3f\n", sigma, compared, worst, moved);
    EXPECT_EQ(compared, known);
    EXPECT_LT(worst, 1e-6) << "sigma " << sigma;  // float sums: 2e-7 measured
    EXPECT_GT(moved, 0.2) << "sigma " << sigma;  // walls next to free space: the blur does move cells
  }
  EXPECT_THROW(rtog::image::blur(g, 0.0), std::invalid_argument);
  EXPECT_THROW(rtog::image::open(occ, 2), std::invalid_argument);
  EXPECT_THROW(rtog::image::bandImage(m->map(), 1, 0), std::invalid_argument);
}

// A real scan of SENA to a Cartesian image and back: every return within a cell and a half.
TEST(GridImage, PolarCartesianRoundTripOfARealScan) {
  const auto frames = loadOdometryFrames(dataset(kSena), 1);
  const auto scan = frames.at(0).sf->getObservationByClass<mrpt::obs::CObservation2DRangeScan>();
  ASSERT_TRUE(scan);
  std::vector<float> ranges(scan->getScanSize());
  for (std::size_t i = 0; i < ranges.size(); ++i) ranges[i] = scan->getScanRangeValidity(i) ? scan->getScanRange(i) : 0.0f;
  const double res = 0.05, max_range = 30.0;
  const cv::Mat img = rtog::image::polarToCartesian(ranges, scan->aperture, max_range, res);
  const auto back = rtog::image::cartesianToPolar(img, ranges.size(), scan->aperture, max_range, res);
  std::size_t returns = 0;
  double worst = 0;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (!(ranges[i] > 0 && ranges[i] <= max_range)) continue;
    ++returns;
    // Another beam's end pixel may lie nearer on this beam's line: never farther.
    EXPECT_LE(back[i], ranges[i] + 1.5 * res) << i;
    worst = std::max(worst, double(std::fabs(back[i] - ranges[i])));
  }
  std::size_t exact = 0;
  for (std::size_t i = 0; i < ranges.size(); ++i)
    exact += ranges[i] > 0 && ranges[i] <= max_range && std::fabs(back[i] - ranges[i]) <= 1.5 * res;
  std::printf("SENA scan: %zu returns, %zu back within 1.5 cells\n", returns, exact);
  EXPECT_GT(returns, 100u);
  EXPECT_GT(double(exact), 0.95 * double(returns));
}

// The seed's check: blurring a 2D view by sigma equals inserting with isotropic position covariance
// sigma^2, within the discretisation. One real SENA scan into an empty map (beam model, 0.05 m):
// (a) from the mean pose, its view blurred by sigma = 0.1 m with unknown cells at the prior;
// (b) from a dense set of poses about the mean (offsets every sigma/4 over +-3 sigma in x and y,
// Gaussian weights), as the pose-uncertainty insertion enters a scan (the mixture of the poses'
// probabilities). The two agree cell by cell far better than the unblurred view agrees with (b).
TEST(GridImage, BlurBySigmaIsInsertionWithPositionCovarianceSigmaSquared) {
  const auto frames = loadOdometryFrames(dataset(kSena), 40);
  const mrpt::obs::CObservation2DRangeScan* scan = nullptr;
  mrpt::poses::CPose3D robot;
  for (const auto& f : frames)
    for (const auto& o : *f.sf)
      if (!scan) {
        scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(o.get());
        robot = f.pose;
      }
  ASSERT_NE(scan, nullptr);
  const mrpt::poses::CPose3D sensor = robot + scan->sensorPose;
  std::vector<Eigen::Vector3f> points;
  for (std::size_t i = 0; i < scan->getScanSize(); ++i) {
    if (!scan->getScanRangeValidity(i)) continue;
    const double r = scan->getScanRange(i), a = scan->getScanAngle(i);
    double x, y, z;
    sensor.composePoint(r * std::cos(a), r * std::sin(a), 0.0, x, y, z);
    points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  }
  ASSERT_GT(points.size(), 100u);
  const Eigen::Vector3d origin(sensor.x(), sensor.y(), sensor.z());
  rtog::MapParams mp;
  mp.resolution = 0.05;
  rtog::InsertParams ip;
  ip.max_range = 15.0;
  rtog::OccupancyMap mean(mp), mixture(mp);
  mean.insertPointCloud(origin, points.data(), points.size(), ip);
  const double sigma = 0.1;
  std::vector<std::vector<Eigen::Vector3f>> moved;
  std::vector<rtog::WeightedScan> poses;
  double total = 0;
  for (int i = -12; i <= 12; ++i)
    for (int j = -12; j <= 12; ++j) total += std::exp(-0.5 * (i * i + j * j) / 16.0);
  moved.reserve(625);
  for (int i = -12; i <= 12; ++i)
    for (int j = -12; j <= 12; ++j) {
      const Eigen::Vector3f shift(static_cast<float>(i * sigma / 4), static_cast<float>(j * sigma / 4), 0.0f);
      moved.emplace_back();
      for (const auto& p : points) moved.back().push_back(p + shift);
      poses.push_back({std::exp(-0.5 * (i * i + j * j) / 16.0) / total, origin + shift.cast<double>(), moved.back().data(),
                       points.size(), nullptr});
    }
  mixture.insertBlurred(poses, ip);
  const GridImage view = rtog::image::bandImage(mean, -1000, 1000);
  const GridImage blurred = rtog::image::blurWithPrior(view, sigma, 0.5);
  const GridImage want = rtog::image::bandImage(mixture, -1000, 1000);
  // Over the cells the mixture knows: P there against the blurred view's and the plain view's.
  const auto at = [](const GridImage& g, std::int32_t kx, std::int32_t ky) {
    const int c = kx - g.x0, r = g.p.rows - 1 - (ky - g.y0);
    if (c < 0 || r < 0 || c >= g.p.cols || r >= g.p.rows) return 0.5f;
    const float v = g.p.at<float>(r, c);
    return std::isnan(v) ? 0.5f : v;
  };
  double d_blur = 0, d_plain = 0, worst_blur = 0;
  std::size_t n = 0;
  for (int r = 0; r < want.p.rows; ++r)
    for (int c = 0; c < want.p.cols; ++c) {
      const float w = want.p.at<float>(r, c);
      if (std::isnan(w)) continue;
      const std::int32_t kx = want.x0 + c, ky = want.y0 + (want.p.rows - 1 - r);
      const double db = std::fabs(at(blurred, kx, ky) - w), dp = std::fabs(at(view, kx, ky) - w);
      d_blur += db, d_plain += dp, worst_blur = std::max(worst_blur, db);
      ++n;
    }
  ASSERT_GT(n, 10000u);
  d_blur /= double(n), d_plain /= double(n);
  std::printf("SENA scan, sigma %.2f m: mean |P| difference from the pose mixture over %zu cells: blurred view %.4f "
              "(largest %.3f), unblurred view %.4f\n",
              sigma, n, d_blur, worst_blur, d_plain);
  EXPECT_LT(d_blur, 0.005);
  EXPECT_LT(worst_blur, 0.05);
  EXPECT_LT(d_blur, 0.1 * d_plain);
}

// A sigma far beyond the image (1 km) and one whose 3 sigma just pass it: the kernel clipped to the
// image gives the weighted means of the known cells with the whole Gaussian's weights (the brute
// force here, in double), at the cost of a kernel the image's size.
TEST(GridImage, ABlurBeyondTheImageIsTheWholeGaussiansWeightedMean) {
  const auto frames = loadOdometryFrames(dataset(kSena), 6);
  auto m = mapFromIni("");
  for (const auto& f : frames)
    for (const auto& obs : *f.sf) m->insertObservation(*obs, f.pose);
  const GridImage g = rtog::image::bandImage(m->map(), -1000, 1000);
  ASSERT_GT(g.p.cols, 50);
  std::vector<std::pair<int, int>> known;
  for (int r = 0; r < g.p.rows; ++r)
    for (int c = 0; c < g.p.cols; ++c)
      if (!std::isnan(g.p.at<float>(r, c))) known.emplace_back(r, c);
  for (const double sigma_px : {20.0, 40.0, 100.0, double(std::max(g.p.rows, g.p.cols)) / 2.5, 20000.0}) {
    const GridImage b = rtog::image::blur(g, sigma_px * g.resolution);
    for (std::size_t k = 0; k < known.size(); k += known.size() / 25) {
      const auto [r, c] = known[k];
      double num = 0, den = 0;
      for (const auto& [qr, qc] : known) {
        const double w = std::exp(-0.5 * (double((qr - r) * (qr - r)) + double((qc - c) * (qc - c))) / (sigma_px * sigma_px));
        num += w * g.p.at<float>(qr, qc), den += w;
      }
      EXPECT_NEAR(b.p.at<float>(r, c), num / den, 1e-3) << "sigma " << sigma_px << " px at (" << r << ", " << c << ")";
    }
  }
}
