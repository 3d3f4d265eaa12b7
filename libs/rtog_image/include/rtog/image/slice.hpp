// Horizontal slices of the grid as images.
#pragma once

#include <cstdint>
#include <string>

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

/// The same slice with each known cell's probability: an 8-bit 3-channel (BGR) image whose known
/// pixels are grey 255 * (1 - P(occupied)) (certainly occupied black, certainly free white, P = 0.5
/// mid grey) and whose unknown pixels are kSliceUnknownColour, so that "no evidence" and
/// "evidence of 0.5" stay apart. Same geometry and errors as rasterizeSliceZ().
cv::Mat rasterizeSliceProbabilityZ(const OccupancyMap& map, double z);
/// Unknown cells of rasterizeSliceProbabilityZ() (BGR: a light blue).
constexpr std::uint8_t kSliceUnknownColour[3] = {235, 206, 135};

/// One of the slices above (by probability or by class) as a picture to look at (picture.hpp):
/// cells scaled up, axes in metres, a scale bar, a legend. Same errors as rasterizeSliceZ().
cv::Mat slicePicture(const OccupancyMap& map, double z, bool probability);
/// slicePicture() written to `path` as PNG band by band (Picture::writePng): for a process that
/// should not hold the whole picture, such as an MRPT app saving its map at the end of its run.
/// Same errors, and std::runtime_error if the file cannot be written.
void writeSlicePicture(const OccupancyMap& map, double z, bool probability, const std::string& path);

}  // namespace rtog::image
