// The pictures the tools write (rtog/image/picture.hpp), on SENA's map: readable without zooming
// (the plot's longer side at least the target, cells scaled by a whole factor) and faithful (each
// cell's pixels are the cell's colour, where the scale bar and the axes do not cover it), with the
// geometry overlays use (toPixel) agreeing with the cells'.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "rtog/image/picture.hpp"
#include "rtog/image/slice.hpp"
#include "test_helpers.hpp"

using namespace rtog_test;

namespace {

const rtog::OccupancyMap& senaMap() {
  static const rtog::OccupancyMap m = [] {
    const auto frames = loadOdometryFrames(dataset(kSena));
    auto ours = mapFromSections("resolution=0.2", "sensorModelPreset=octomap\n");  // some 260 cells across
    for (std::size_t i = 0; i < frames.size(); i += 4)
      for (const auto& obs : *frames[i].sf) ours->insertObservation(*obs, frames[i].pose);
    return ours->map();
  }();
  return m;
}

/// The share of cells whose whole pixel block in `img` is the cell's colour.
double faithfulShare(const rtog::image::Picture& pic, const cv::Mat& cells, const cv::Mat& img) {
  std::size_t same = 0;
  for (int r = 0; r < cells.rows; ++r)
    for (int c = 0; c < cells.cols; ++c) {
      const cv::Vec3b want = cells.channels() == 1 ? cv::Vec3b::all(cells.at<std::uint8_t>(r, c)) : cells.at<cv::Vec3b>(r, c);
      const cv::Mat block = img(pic.cellRect(c, r));
      bool all = true;
      for (int y = 0; y < block.rows && all; ++y)
        for (int x = 0; x < block.cols && all; ++x) all = block.at<cv::Vec3b>(y, x) == want;
      same += all;
    }
  return double(same) / double(cells.total());
}

}  // namespace

TEST(Picture, SlicePictureIsReadableAndShowsEveryCell) {
  const rtog::OccupancyMap& m = senaMap();
  const double z = 0.5 * m.resolution();
  for (const bool probability : {false, true}) {
    const cv::Mat cells = probability ? rtog::image::rasterizeSliceProbabilityZ(m, z) : rtog::image::rasterizeSliceZ(m, z);
    const cv::Mat img = rtog::image::slicePicture(m, z, probability);
    const rtog::Box b = m.keyBounds();
    const Eigen::Vector3d lo = m.lattice().boxMin(b);
    const rtog::image::Picture pic(cells, lo.x(), lo.y(), m.resolution());
    // Fewer cells than the target across: scaled up to at least 800 pixels.
    ASSERT_LT(std::max(cells.cols, cells.rows), 800);
    EXPECT_GE(pic.scale(), 2);
    EXPECT_GE(std::max(pic.plotArea().width, pic.plotArea().height), 800);
    EXPECT_LT(std::max(pic.plotArea().width, pic.plotArea().height), 800 + 2 * std::max(cells.cols, cells.rows));
    ASSERT_EQ(img.type(), CV_8UC3);
    EXPECT_GT(img.cols, pic.plotArea().br().x);  // the legend beside the plot
    EXPECT_GT(img.rows, pic.plotArea().br().y);  // the x axis's labels below it
    // The scale bar and MRPT's axes at the origin cover a little of the plot; the rest is the cells.
    const double share = faithfulShare(pic, cells, img);
    EXPECT_GT(share, 0.97) << "probability " << probability;
    EXPECT_LT(share, 1.0) << "the scale bar is drawn over the plot";
    // Overlays land on the cells: the centre of cell (c, r) in metres is inside its block.
    for (const auto& [c, r] : {std::pair{0, 0}, {cells.cols - 1, cells.rows - 1}, {cells.cols / 3, cells.rows / 2}}) {
      const Eigen::Vector2d centre(lo.x() + (c + 0.5) * m.resolution(), lo.y() + (cells.rows - 1 - r + 0.5) * m.resolution());
      EXPECT_TRUE(pic.cellRect(c, r).contains(pic.toPixel(centre))) << c << " " << r;
    }
  }
}

// The picture written band by band (an app's end save) is the picture drawn whole, pixel for pixel.
TEST(Picture, ASlicePictureWrittenByBandsIsThePictureDrawnWhole) {
  const rtog::OccupancyMap& m = senaMap();
  const double z = 0.5 * m.resolution();
  const std::string path = (std::filesystem::temp_directory_path() / "rtog_banded_slice.png").string();
  for (const bool probability : {false, true}) {
    const cv::Mat whole = rtog::image::slicePicture(m, z, probability);
    rtog::image::writeSlicePicture(m, z, probability, path);
    const cv::Mat banded = cv::imread(path, cv::IMREAD_COLOR);
    ASSERT_EQ(banded.size(), whole.size()) << "probability " << probability;
    ASSERT_GT(whole.rows, 64 * 3) << "the picture must span several bands";
    cv::Mat diff;
    cv::absdiff(whole, banded, diff);
    EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << "probability " << probability;
  }
  std::filesystem::remove(path);
  EXPECT_THROW(rtog::image::writeSlicePicture(m, z, false, "/nonexistent-dir/x.png"), std::runtime_error);
}

TEST(Picture, BigGridsKeepOnePixelACellAndBadInputIsRefused) {
  const cv::Mat cells(900, 1200, CV_8UC1, cv::Scalar(128));
  const rtog::image::Picture pic(cells, -3.0, 2.0, 0.1);
  EXPECT_EQ(pic.scale(), 1);
  EXPECT_EQ(pic.plotArea().size(), cells.size());
  EXPECT_THROW(rtog::image::Picture(cv::Mat(), 0, 0, 0.1), std::invalid_argument);
  EXPECT_THROW(rtog::image::Picture(cells, 0, 0, 0.0), std::invalid_argument);
  EXPECT_THROW(rtog::image::Picture(cells, 0, 0, std::nan("")), std::invalid_argument);
}
