// A map of the bundled TUM depth frames, for the tests that need a real 3D map.
#pragma once

#include <cstddef>

#include "rtog/core/occupancy_map.hpp"
#include "rtog/image/tum_dataset.hpp"

namespace rtog::test {

/// Every `frame_stride`-th frame of the sequence in `dir`, every `pixel_stride`-th pixel, beams cut at 4 m.
inline OccupancyMap tumMap(const char* dir, const MapParams& params, std::size_t frame_stride, int pixel_stride) {
  const image::DepthSequence seq = image::readTumSequence(dir);
  OccupancyMap map(params);
  InsertParams ip;
  ip.max_range = 4.0;
  for (std::size_t i = 0; i < seq.frames.size(); i += frame_stride) {
    const image::WorldScan s = image::loadDepthScan(seq.frames[i], seq.intrinsics, pixel_stride);
    map.insertPointCloud(s.origin, s.points, ip);
  }
  return map;
}

}  // namespace rtog::test
