// rtog::CRTreeOccupancyGridMap: observation likelihood (likelihood field and ray tracing).
#include <cmath>
#include <cstring>
#include <mutex>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

bool CRTreeOccupancyGridMap::internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const {
  using namespace mrpt::obs;
  if (isEmpty()) return false;
  return dynamic_cast<const CObservation2DRangeScan*>(&obs) || dynamic_cast<const CObservationPointCloud*>(&obs) ||
         dynamic_cast<const CObservationVelodyneScan*>(&obs) || dynamic_cast<const CObservationRotatingScan*>(&obs) ||
         dynamic_cast<const CObservation3DRangeScan*>(&obs);
}

double CRTreeOccupancyGridMap::internal_computeObservationLikelihood(const mrpt::obs::CObservation& obs,
                                                                     const mrpt::poses::CPose3D& takenFrom) const {
  ObservationBeams beams;
  if (!extractBeams(obs, takenFrom, beams, false)) return 0.0;  // no information: neutral
  return beamsLikelihood(beams);
}

double CRTreeOccupancyGridMap::beamsLikelihood(const ObservationBeams& b) const {
  likelihoodOptions.validate();
  return likelihoodOptions.likelihoodMethod == lmRayTracing ? rayTracing(b) : likelihoodField(b);
}

float CRTreeOccupancyGridMap::distanceToOccupiedLocked(const Eigen::Vector3d& p) const {
  const float cap = likelihoodOptions.LF_maxCorrsDistance;
  Key k;
  if (!map_.lattice().tryKey(p, k)) return cap;
  if (!likelihoodOptions.enableLikelihoodCache) {
    const auto h = map_.nearestOccupied(p, cap);
    return h.found ? static_cast<float>(std::min<double>(h.distance, cap)) : cap;
  }
  // Cached per lattice cell: the distance from the cell centre.
  const std::uint64_t pk = packKey(k);
  std::uint32_t bits = caches_.lf.find(pk);
  float d;
  if (bits != detail::FlatHashMap64::kAbsent) {
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  const auto h = map_.nearestOccupied(map_.lattice().cellCenter(k), cap);
  d = h.found ? static_cast<float>(std::min<double>(h.distance, cap)) : cap;
  std::memcpy(&bits, &d, sizeof d);  // a distance is never NaN, so never kAbsent's bits
  caches_.lf.findOrInsert(pk, bits);
  return d;
}

double CRTreeOccupancyGridMap::likelihoodField(const ObservationBeams& b) const {
  const auto& o = likelihoodOptions;
  const double inv2var = 1.0 / (2.0 * double(o.LF_stdHit) * o.LF_stdHit);
  const double zRandomTerm = double(o.LF_zRandom) / o.LF_maxRange;
  double sum = 0.0;
  // One lock per scan, not per point: a particle filter calls this for every particle.
  std::lock_guard<std::mutex> lk(caches_.mutex);
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    if (!b.is_hit[i] || b.ranges[i] > o.LF_maxRange) continue;
    const double d = distanceToOccupiedLocked(b.points[i].cast<double>());
    if (o.LF_useSquareDist)
      sum -= d * d * inv2var;
    else
      sum += std::log(zRandomTerm + o.LF_zHit * std::exp(-d * d * inv2var));
  }
  return sum;
}

double CRTreeOccupancyGridMap::rayTracing(const ObservationBeams& b) const {
  const auto& o = likelihoodOptions;
  const double inv2var = 1.0 / (2.0 * double(o.rayTracing_stdHit) * o.rayTracing_stdHit);
  const double maxRange = o.LF_maxRange;
  const double zRandomTerm = double(o.LF_zRandom) / o.LF_maxRange;
  double sum = 0.0;
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    if (!b.is_hit[i] || b.ranges[i] > maxRange) continue;
    const Eigen::Vector3d dir = b.points[i].cast<double>() - b.origin;
    if (!(dir.squaredNorm() > 0)) continue;
    const auto hit = map_.castRay(b.origin, dir, maxRange);
    const double expected = hit.hit ? hit.distance : maxRange;
    const double e = double(b.ranges[i]) - expected;
    // Gaussian around the ray-traced range mixed with a uniform term (LF_zHit / LF_zRandom),
    // so that beams through unmapped space cannot dominate.
    sum += std::log(zRandomTerm + o.LF_zHit * std::exp(-e * e * inv2var));
  }
  return sum;
}

}  // namespace rtog
