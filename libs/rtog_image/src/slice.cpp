#include "rtog/image/slice.hpp"

#include "rtog/image/picture.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace rtog::image {
namespace {

/// The slice's bounds and z key, checked; the image's size.
Box sliceGeometry(const OccupancyMap& map, double z, Key& zk) {
  const Box bounds = map.keyBounds();
  if (bounds.isEmpty()) throw std::invalid_argument("the map is empty: there is no slice to draw");
  if (!map.lattice().tryKey(Eigen::Vector3d(0.0, 0.0, z), zk))
    throw std::invalid_argument("slice height " + std::to_string(z) + " m has no cell key");
  const std::int64_t w = bounds.extent(0), h = bounds.extent(1);
  if (w * h > (std::int64_t{1} << 28))
    throw std::length_error("a slice of " + std::to_string(w) + " x " + std::to_string(h) +
                            " pixels is too large");
  return bounds;
}

/// Calls fill(row, column, log-odds) for every known cell of the slice.
template <class Fill>
void forEachSliceCell(const OccupancyMap& map, const Box& bounds, const Key& zk, Fill&& fill) {
  map.forEachLeaf([&](const Box& b, float v) {
    if (zk.z < b.min.z || zk.z > b.max.z) return;
    for (std::int32_t y = b.min.y; y <= b.max.y; ++y)
      for (std::int32_t x = b.min.x; x <= b.max.x; ++x) fill(bounds.max.y - y, x - bounds.min.x, v);
  });
}

/// A known cell's grey: in the occupancy slice, by its state; in the probability slice, 255 (1 - P).
std::uint8_t stateGrey(const LogOddsModel& model, float v) {
  return model.classify(v) == CellState::Occupied ? kSliceOccupied : kSliceFree;
}
std::uint8_t probabilityGrey(float v) {
  const double p = 1.0 / (1.0 + std::exp(-double(v)));
  return static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - p)));
}

}  // namespace

cv::Mat rasterizeSliceZ(const OccupancyMap& map, double z) {
  Key zk;
  const Box bounds = sliceGeometry(map, z, zk);
  cv::Mat img(static_cast<int>(bounds.extent(1)), static_cast<int>(bounds.extent(0)), CV_8UC1,
              cv::Scalar(kSliceUnknown));
  const LogOddsModel& model = map.logOddsModel();
  forEachSliceCell(map, bounds, zk, [&](std::int64_t r, std::int64_t c, float v) {
    img.ptr<std::uint8_t>(static_cast<int>(r))[c] = stateGrey(model, v);
  });
  return img;
}

cv::Mat rasterizeSliceProbabilityZ(const OccupancyMap& map, double z) {
  Key zk;
  const Box bounds = sliceGeometry(map, z, zk);
  cv::Mat img(static_cast<int>(bounds.extent(1)), static_cast<int>(bounds.extent(0)), CV_8UC3,
              cv::Scalar(kSliceUnknownColour[0], kSliceUnknownColour[1], kSliceUnknownColour[2]));
  forEachSliceCell(map, bounds, zk, [&](std::int64_t r, std::int64_t c, float v) {
    std::uint8_t* px = img.ptr<std::uint8_t>(static_cast<int>(r)) + 3 * c;
    px[0] = px[1] = px[2] = probabilityGrey(v);
  });
  return img;
}

namespace {

/// The picture's title and legend for a slice at `z`.
PictureOptions sliceOptions(double z, bool probability) {
  PictureOptions o;
  char title[64];
  std::snprintf(title, sizeof title, "slice at z = %g m", z);
  o.title = title;
  const auto grey = [](std::uint8_t g) { return cv::Vec3b(g, g, g); };
  if (probability) {
    o.legend = {{cv::Vec3b(kSliceUnknownColour[0], kSliceUnknownColour[1], kSliceUnknownColour[2]), "unknown"}};
    o.probability_ramp = true;
  } else {
    o.legend = {{grey(kSliceOccupied), "occupied"}, {grey(kSliceFree), "free"}, {grey(kSliceUnknown), "unknown"}};
  }
  return o;
}

}  // namespace

cv::Mat slicePicture(const OccupancyMap& map, double z, bool probability) {
  Key zk;
  const Box bounds = sliceGeometry(map, z, zk);
  const Eigen::Vector3d lo = map.lattice().boxMin(bounds);
  const cv::Vec3b unknown = probability ? cv::Vec3b(kSliceUnknownColour[0], kSliceUnknownColour[1], kSliceUnknownColour[2])
                                        : cv::Vec3b(kSliceUnknown, kSliceUnknown, kSliceUnknown);
  // The cells painted into the picture as they come: an image of them beside the canvas would
  // be a second copy of the slice.
  Picture pic(static_cast<int>(bounds.extent(1)), static_cast<int>(bounds.extent(0)), unknown, lo.x(), lo.y(),
              map.resolution(), sliceOptions(z, probability));
  const LogOddsModel& model = map.logOddsModel();
  forEachSliceCell(map, bounds, zk, [&](std::int64_t r, std::int64_t c, float v) {
    const std::uint8_t g = probability ? probabilityGrey(v) : stateGrey(model, v);
    pic.paintCell(static_cast<int>(c), static_cast<int>(r), cv::Vec3b(g, g, g));
  });
  return pic.finish();  // shares the canvas, which outlives the picture
}

void writeSlicePicture(const OccupancyMap& map, double z, bool probability, const std::string& path) {
  const cv::Mat cells = probability ? rasterizeSliceProbabilityZ(map, z) : rasterizeSliceZ(map, z);
  const Eigen::Vector3d lo = map.lattice().boxMin(map.keyBounds());
  Picture::writePng(path, cells, lo.x(), lo.y(), map.resolution(), sliceOptions(z, probability));
}

}  // namespace rtog::image
