// rtog::CRTreeOccupancyGridMap: ICP support (correspondences against occupied cells).
#include <algorithm>
#include <limits>
#include <mutex>

#include <mrpt/maps/CPointsMap.h>
#include <mrpt/poses/CPose2D.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "CRTreeOccupancyGridMap_caches.hpp"

namespace rtog {

using namespace mrpt::maps;

const CSimplePointsMap& CRTreeOccupancyGridMap::occupiedCellCentersForMatching2D() const {
  const float lo = matchingOptions.matching2D_minZ, hi = matchingOptions.matching2D_maxZ;
  const Box kb = map_.keyBounds();
  const Lattice& lat = map_.lattice();
  if (kb.isEmpty() || (lat.cellCenter(kb.min).z() >= lo && lat.cellCenter(kb.max).z() <= hi))
    return occupiedCellCenters();  // the band holds every cell
  const CSimplePointsMap& all = occupiedCellCenters();
  std::lock_guard<std::mutex> lk(caches_->mutex);
  if (caches_->band_points_dirty || caches_->band_lo != lo || caches_->band_hi != hi) {
    auto& pts = caches_->band_points;
    pts.clear();
    const auto& xs = all.getPointsBufferRef_x();
    const auto& ys = all.getPointsBufferRef_y();
    const auto& zs = all.getPointsBufferRef_z();
    for (std::size_t i = 0; i < xs.size(); ++i)
      if (zs[i] >= lo && zs[i] <= hi) pts.insertPointFast(xs[i], ys[i], zs[i]);
    pts.mark_as_modified();
    caches_->band_lo = lo;
    caches_->band_hi = hi;
    caches_->band_points_dirty = false;
  }
  return caches_->band_points;
}

// Correspondences pair each point of `otherMap` with the centre of an occupied cell within the
// 2D height band; the work is done by MRPT's points-map matcher on the cached cloud of those
// cell centres.
void CRTreeOccupancyGridMap::determineMatching2D(const CMetricMap* otherMap, const mrpt::poses::CPose2D& otherMapPose,
                                                 mrpt::tfest::TMatchingPairList& correspondences,
                                                 const TMatchingParams& params,
                                                 TMatchingExtraResults& extraResults) const {
  correspondences.clear();
  extraResults = TMatchingExtraResults();
  const CSimplePointsMap& occ = occupiedCellCentersForMatching2D();
  if (occ.empty() || !otherMap || otherMap->isEmpty()) return;
  occ.determineMatching2D(otherMap, otherMapPose, correspondences, params, extraResults);
}

// 3D: each point of `otherMap` (decimated as asked) is paired with the centre of the cell of the
// nearest occupied cuboid that is closest to it, found in the R-tree; `globalIdx` is the index of
// the other map's point (a cuboid has no point index).
void CRTreeOccupancyGridMap::determineMatching3D(const CMetricMap* otherMap, const mrpt::poses::CPose3D& otherMapPose,
                                                 mrpt::tfest::TMatchingPairList& correspondences,
                                                 const TMatchingParams& params,
                                                 TMatchingExtraResults& extraResults) const {
  correspondences.clear();
  extraResults = TMatchingExtraResults();
  if (!otherMap || isEmpty()) return;
  const CPointsMap* pts = dynamic_cast<const CPointsMap*>(otherMap);
  if (!pts) pts = otherMap->getAsSimplePointsMap();
  if (!pts || pts->empty()) return;
  const auto& xs = pts->getPointsBufferRef_x();
  const auto& ys = pts->getPointsBufferRef_y();
  const auto& zs = pts->getPointsBufferRef_z();
  const std::size_t step = std::max<std::size_t>(params.decimation_other_map_points, 1);
  const Lattice& lat = map_.lattice();
  const auto& pv = params.angularDistPivotPoint;
  std::size_t considered = 0;
  for (std::size_t i = params.offset_other_map_points; i < xs.size(); i += step) {
    ++considered;
    double gx, gy, gz;
    otherMapPose.composePoint(xs[i], ys[i], zs[i], gx, gy, gz);
    const Eigen::Vector3d g(gx, gy, gz);
    const double maxd = params.maxDistForCorrespondence +
                        params.maxAngularDistForCorrespondence * (g - Eigen::Vector3d(pv.x, pv.y, pv.z)).norm();
    const auto h = map_.nearestOccupied(g, maxd);
    if (!h.found) continue;
    // The cell of the cuboid nearest to the point.
    const Eigen::Vector3d lo = lat.boxMin(h.leaf), hi = lat.boxMax(h.leaf);
    Key k;
    if (!lat.tryKey(g.cwiseMax(lo).cwiseMin(hi - Eigen::Vector3d::Constant(1e-9)), k)) continue;
    const Eigen::Vector3d c = lat.cellCenter(k);
    mrpt::tfest::TMatchingPair pair(static_cast<uint32_t>(i), static_cast<uint32_t>(i), c.x(), c.y(), c.z(), xs[i],
                                    ys[i], zs[i]);
    pair.errorSquareAfterTransformation = static_cast<float>((c - g).squaredNorm());
    extraResults.sumSqrDist += pair.errorSquareAfterTransformation;
    correspondences.push_back(pair);
  }
  // The mean over the pairs, as CPointsMap::determineMatching3D reports it (despite the name).
  if (!correspondences.empty()) extraResults.sumSqrDist /= static_cast<double>(correspondences.size());
  extraResults.correspondencesRatio = considered ? float(correspondences.size()) / float(considered) : 0.0f;
}

float CRTreeOccupancyGridMap::compute3DMatchingRatio(const CMetricMap* otherMap,
                                                     const mrpt::poses::CPose3D& otherMapPose,
                                                     const TMatchingRatioParams& params) const {
  if (!otherMap || isEmpty()) return 0.0f;
  const CPointsMap* pts = dynamic_cast<const CPointsMap*>(otherMap);
  if (!pts) pts = otherMap->getAsSimplePointsMap();
  if (!pts || pts->empty()) return 0.0f;
  const auto& xs = pts->getPointsBufferRef_x();
  const auto& ys = pts->getPointsBufferRef_y();
  const auto& zs = pts->getPointsBufferRef_z();
  std::size_t matched = 0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    double gx, gy, gz;
    otherMapPose.composePoint(xs[i], ys[i], zs[i], gx, gy, gz);
    if (map_.nearestOccupied(Eigen::Vector3d(gx, gy, gz), params.maxDistForCorr).found) ++matched;
  }
  return static_cast<float>(double(matched) / double(xs.size()));
}

float CRTreeOccupancyGridMap::squareDistanceToClosestCorrespondence(float x0, float y0) const {
  const CSimplePointsMap& occ = occupiedCellCentersForMatching2D();
  if (occ.empty()) return std::numeric_limits<float>::max();
  return occ.squareDistanceToClosestCorrespondence(x0, y0);
}

}  // namespace rtog
