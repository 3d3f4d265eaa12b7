// Horizontal slices of the grid as images.
#pragma once

#include <cstdint>

#include <opencv2/core/mat.hpp>

#include "rtog/core/occupancy_map.hpp"

namespace rtog::image {

constexpr std::uint8_t kSliceOccupied = 0;   ///< black
constexpr std::uint8_t kSliceFree = 255;     ///< white
constexpr std::uint8_t kSliceUnknown = 128;  ///< grey

/// The layer of cells containing height `z` [m] as an 8-bit single-channel image with one
/// pixel per cell over the map's x/y key bounds (`map.keyBounds()`): occupied kSliceOccupied,
/// free kSliceFree, unknown kSliceUnknown. y points up: pixel (row r, column c) is the cell
/// `{bounds.min.x + c, bounds.max.y - r, key of z}`. A z outside the map's height range gives
/// an all-unknown image. Throws std::invalid_argument for an empty map or a z without a key,
/// and std::length_error if the image would exceed 2^28 pixels.
cv::Mat rasterizeSliceZ(const OccupancyMap& map, double z);

}  // namespace rtog::image
