// rtog::CRTreeOccupancyGridMap: observation likelihood (likelihood field and ray tracing).
#include <cmath>
#include <cstring>
#include <mutex>

#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/obs/CObservationRotatingScan.h>
#include <mrpt/obs/CObservationVelodyneScan.h>

#include "finite_pose.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "CRTreeOccupancyGridMap_caches.hpp"

namespace rtog {

using detail::kImpossibleLogLik;

bool CRTreeOccupancyGridMap::internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const {
  using namespace mrpt::obs;
  if (isEmpty()) return false;
  return dynamic_cast<const CObservation2DRangeScan*>(&obs) || dynamic_cast<const CObservationPointCloud*>(&obs) ||
         dynamic_cast<const CObservationVelodyneScan*>(&obs) || dynamic_cast<const CObservationRotatingScan*>(&obs) ||
         dynamic_cast<const CObservation3DRangeScan*>(&obs) || dynamic_cast<const CObservationRange*>(&obs);
}

double CRTreeOccupancyGridMap::internal_computeObservationLikelihood(const mrpt::obs::CObservation& obs,
                                                                     const mrpt::poses::CPose3D& takenFrom) const {
  // First: a non-finite pose would also grow the 2D view without bound; a NaN angle of the
  // sensor pose makes every end point NaN, and a sum without a beam would be the best score.
  if (!detail::finitePoses(obs, takenFrom)) return kImpossibleLogLik;
  // Planar 2D scans: MRPT's own method on the 2D view (see scanLikelihoodOnGridView).
  if (const std::optional<double> l = gridViewLikelihood(obs, takenFrom)) return *l;
  // Per thread and kept: a particle filter calls this for every particle.
  thread_local ObservationBeams beams;
  if (!extractBeams(obs, takenFrom, beams, false)) return 0.0;  // no information: neutral
  return beamsLikelihood(beams);
}

double CRTreeOccupancyGridMap::beamsLikelihood(const ObservationBeams& b) const {
  likelihoodOptions.validate();
  if (!b.origin.allFinite()) return kImpossibleLogLik;  // e.g. a NaN sensor pose on the robot
  // 3D beams: the native ray tracing, or the native likelihood field for every other method
  // (MRPT defines those on planar scans only).
  return likelihoodOptions.likelihoodMethod == lmRayTracing ? rayTracing(b) : likelihoodField(b);
}

float CRTreeOccupancyGridMap::fieldTermLocked(const Eigen::Vector3d& p, const FieldParams& f) const {
  const auto termAt = [&](double d) {
    return static_cast<float>(f.squareDist ? -d * d * f.inv2var
                                           : std::log(f.zRandomTerm + f.zHit * std::exp(-d * d * f.inv2var)));
  };
  const auto term = [&](const Eigen::Vector3d& q) {
    const auto h = map_.nearestOccupied(q, f.cap);
    return termAt(h.found ? std::min<double>(h.distance, f.cap) : f.cap);
  };
  Key k;
  if (!map_.lattice().tryKey(p, k)) return termAt(f.cap);  // beyond the key range: nothing near
  if (!likelihoodOptions.enableLikelihoodCache) return term(p);
  // Cached per lattice cell: the term at the cell centre.
  const std::uint64_t pk = packKey(k);
  std::uint32_t bits = caches_->lf.find(pk);
  float t;
  if (bits != detail::FlatHashMap64::kAbsent) {
    std::memcpy(&t, &bits, sizeof t);
    return t;
  }
  t = term(map_.lattice().cellCenter(k));
  std::memcpy(&bits, &t, sizeof t);
  if (bits != detail::FlatHashMap64::kAbsent) caches_->lf.findOrInsert(pk, bits);  // a finite term never is
  return t;
}

double CRTreeOccupancyGridMap::likelihoodField(const ObservationBeams& b) const {
  const auto& o = likelihoodOptions;
  const FieldParams f{1.0 / (2.0 * double(o.LF_stdHit) * o.LF_stdHit), o.LF_zHit, double(o.LF_zRandom) / o.LF_maxRange,
                      o.LF_maxCorrsDistance, o.LF_useSquareDist};
  double sum = 0.0;
  // One lock per scan, not per point: a particle filter calls this for every particle.
  std::lock_guard<std::mutex> lk(caches_->mutex);
  if (!caches_->lf_params || !(*caches_->lf_params == f)) {  // options changed since the terms were cached
    caches_->lf.clear();
    caches_->lf_params = f;
  }
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    if (!b.is_hit[i] || b.ranges[i] > o.LF_maxRange) continue;
    sum += fieldTermLocked(b.points[i].cast<double>(), f);
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
