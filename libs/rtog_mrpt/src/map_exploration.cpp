#include "rtog/mrpt/map_exploration.h"

#include <mrpt/math/CMatrixFixed.h>

namespace rtog {

std::vector<FrontierRegion> frontierRegions(const CRTreeOccupancyGridMap& map, const FrontierOptions& options) {
  return frontierRegions(map.map(), options);
}

std::vector<TMapView> nextBestViews(const CRTreeOccupancyGridMap& map, const mrpt::math::TPoint3D& from,
                                    const ViewOptions& options) {
  std::vector<TMapView> out;
  for (const View& v : nextBestViews(map.map(), Eigen::Vector3d(from.x, from.y, from.z), options))
    out.push_back(TMapView{toCPose3D(v.pose), v});
  return out;
}

FieldValue occupancyAt(const CRTreeOccupancyGridMap& map, const mrpt::math::TPoint3D& p) {
  return occupancyAt(map.map(), Eigen::Vector3d(p.x, p.y, p.z));
}

mrpt::poses::CPose3D toCPose3D(const Eigen::Isometry3d& t) {
  mrpt::math::CMatrixDouble44 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = t.matrix()(r, c);
  return mrpt::poses::CPose3D(m);
}

}  // namespace rtog
