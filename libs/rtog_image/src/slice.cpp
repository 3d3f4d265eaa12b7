#include "rtog/image/slice.hpp"

#include <stdexcept>
#include <string>

namespace rtog::image {

cv::Mat rasterizeSliceZ(const OccupancyMap& map, double z) {
  const Box bounds = map.keyBounds();
  if (bounds.isEmpty()) throw std::invalid_argument("the map is empty: there is no slice to draw");
  Key zk;
  if (!map.lattice().tryKey(Eigen::Vector3d(0.0, 0.0, z), zk))
    throw std::invalid_argument("slice height " + std::to_string(z) + " m has no cell key");
  const std::int64_t w = bounds.extent(0), h = bounds.extent(1);
  if (w * h > (std::int64_t{1} << 28))
    throw std::length_error("a slice of " + std::to_string(w) + " x " + std::to_string(h) +
                            " pixels is too large");
  cv::Mat img(static_cast<int>(h), static_cast<int>(w), CV_8UC1, cv::Scalar(kSliceUnknown));
  const LogOddsModel& model = map.logOddsModel();
  map.forEachLeaf([&](const Box& b, float v) {
    if (zk.z < b.min.z || zk.z > b.max.z) return;
    const std::uint8_t px = model.classify(v) == CellState::Occupied ? kSliceOccupied : kSliceFree;
    for (std::int32_t y = b.min.y; y <= b.max.y; ++y) {
      std::uint8_t* row = img.ptr<std::uint8_t>(bounds.max.y - y);
      for (std::int32_t x = b.min.x; x <= b.max.x; ++x) row[x - bounds.min.x] = px;
    }
  });
  return img;
}

}  // namespace rtog::image
