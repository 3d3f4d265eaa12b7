// Exploration on the MRPT map (doc/exploration.md): its frontier regions, next-best views as MRPT
// poses and the occupancy field O(x), by the core's rules (rtog/core/explore.hpp) on the map's cells.
#pragma once

#include <vector>

#include <mrpt/math/TPoint3D.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/core/explore.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

/// The map's frontier regions (frontierRegions on its cells).
std::vector<FrontierRegion> frontierRegions(const CRTreeOccupancyGridMap& map, const FrontierOptions& options = {});

/// A next-best view with its sensor pose as an MRPT pose.
struct TMapView {
  mrpt::poses::CPose3D pose;
  View view;
};

/// The next-best views from `from` (nextBestViews on the map's cells), best first.
std::vector<TMapView> nextBestViews(const CRTreeOccupancyGridMap& map, const mrpt::math::TPoint3D& from,
                                    const ViewOptions& options);

/// O(x) at `p` (occupancyAt on the map's cells).
FieldValue occupancyAt(const CRTreeOccupancyGridMap& map, const mrpt::math::TPoint3D& p);

/// An isometry as an MRPT pose.
mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& t);

}  // namespace rtog
