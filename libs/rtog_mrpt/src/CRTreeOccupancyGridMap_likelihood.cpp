// rtog::CRTreeOccupancyGridMap: observation likelihood (likelihood field and ray tracing of
// beams; planar scans and sonar readings on the 2D view, sonar_cones.hpp for the latter).
#include <algorithm>
#include <array>
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
#include "CRTreeOccupancyGridMap_grid2d.hpp"
#include "grid_consensus.hpp"
#include "mrpt_grid.hpp"
#include "sonar_cones.hpp"

namespace rtog {

using detail::kImpossibleLogLik;

namespace {
/// COccupancyGridMap2D's default tolerance of a planar scan, which its 2D view (and the stock grid
/// of a pasted section, which has no key for it) holds.
const float kPlanarTolerance = mrpt::maps::COccupancyGridMap2D::TInsertionOptions().horizontalTolerance;
}  // namespace

bool CRTreeOccupancyGridMap::internal_canComputeObservationLikelihood(const mrpt::obs::CObservation& obs) const {
  using namespace mrpt::obs;
  // In the mrpt_grid preset as COccupancyGridMap2D: a planar scan can be scored on an empty map
  // (its grid of the creation extent, all unknown), and particle filters ask before they weigh.
  if (insertionOptions.mrptGrid() && likelihoodOptions.scanLikelihoodOnGridView)
    if (const auto* scan = dynamic_cast<const CObservation2DRangeScan*>(&obs))
      return scan->isPlanarScan(kPlanarTolerance) &&
             !(insertionOptions.useMapAltitude && std::fabs(insertionOptions.mapAltitude - scan->sensorPose.z()) > 0.01);
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


std::optional<double> CRTreeOccupancyGridMap::gridViewLikelihood(const mrpt::obs::CObservation& obs,
                                                                 const mrpt::poses::CPose3D& pose) const {
  if (!likelihoodOptions.scanLikelihoodOnGridView) return std::nullopt;
  if (const auto* range = dynamic_cast<const mrpt::obs::CObservationRange*>(&obs)) {
    likelihoodOptions.validate();
    if (!sonar::scorable(*range, pose)) return std::nullopt;
    const auto v = gridViewShared(nullptr);
    std::lock_guard<std::mutex> lk(v->mutex);
    return sonar::likelihood(*range, pose, likelihoodOptions, v->grid);
  }
  const auto* scan = dynamic_cast<const mrpt::obs::CObservation2DRangeScan*>(&obs);
  if (!scan) return std::nullopt;
  // Non-finite poses (of the robot or of the sensor on it) and tilted scans are left to the
  // native 3D path, which scores the former as impossible.
  // Both poses checked apart, not composed: a particle filter calls this for every particle, and
  // reading the angles of a composed pose costs more than the rest of this wrapper.
  for (const mrpt::poses::CPose3D* p : {&pose, &scan->sensorPose})
    if (!(std::isfinite(p->x()) && std::isfinite(p->y()) && std::isfinite(p->z()) && std::isfinite(p->yaw()) &&
          std::isfinite(p->pitch()) && std::isfinite(p->roll())))
      return std::nullopt;
  likelihoodOptions.validate();
  if (!scan->isPlanarScan(kPlanarTolerance)) return std::nullopt;
  // MRPT's lmConsensus reads the cells of end points without a bounds check: for it the view
  // is grown to hold them (beyond the stock grid, where that grid's result is undefined). The
  // others check bounds (getCell, or the field's own test) and run on the view as it is.
  const auto method = likelihoodOptions.likelihoodMethod;
  std::optional<std::array<double, 4>> need;
  // Consensus, MI and cells-difference read or write the cells of every valid end point: a
  // "valid" range that is not finite, negative (an end point behind the sensor) or beyond the
  // scan's maxRange or 100 km (beyond any range sensor) is taken as no return for them, on a
  // copy made only for a scan that has one. (Not the insertion range: the stock grid scores
  // beams beyond it, and so must the view.)
  std::optional<mrpt::obs::CObservation2DRangeScan> trimmed;  // made only when needed: a scan is a heavy object
  const mrpt::obs::CObservation2DRangeScan* scored = scan;
  if (method == lmConsensus || method == lmMeanInformation || method == lmCellsDifference) {
    // MRPT puts beam i at angle aperture * (i / (n - 1) - 1/2): a non-finite aperture gives NaN end
    // points, whose cells these methods would read at an undefined index; a single beam MRPT
    // refuses by an assertion (nRays >= 2 in its sin/cos table). Both are scored by the native
    // path, which counts NaN beams as invalid and casts one beam as the insertion does.
    if (!std::isfinite(scan->aperture) || scan->getScanSize() < 2) return std::nullopt;
    const float limit = scan->maxRange > 0.0f ? std::min(scan->maxRange, 1e5f) : 1e5f;
    const auto farOrBad = [&](std::size_t i) {
      const float r = scan->getScanRange(i);
      return scan->getScanRangeValidity(i) && !(std::isfinite(r) && r >= 0.0f && r <= limit);
    };
    // A pose whose scan cannot reach the map's cells is left to the native path: the view or
    // grid would grow from the map to a particle flung far away. It must hold the robot and the
    // sensor (which may be mounted, or misconfigured, far off); composed here only, as these
    // methods cost far more than the composition. Written so that a NaN is refused too.
    const Box kb = map_.keyBounds();
    if (kb.isEmpty()) return std::nullopt;
    const Eigen::Vector3d lo = map_.lattice().boxMin(kb), hi = map_.lattice().boxMax(kb);
    const double reach = limit + 1.0;
    const mrpt::poses::CPose3D sensor = pose + scan->sensorPose;
    for (const mrpt::poses::CPose3D* p : {&pose, &sensor})
      if (!(p->x() >= lo.x() - reach && p->y() >= lo.y() - reach && p->x() <= hi.x() + reach && p->y() <= hi.y() + reach))
        return std::nullopt;
    std::size_t i = 0;
    while (i < scan->getScanSize() && !farOrBad(i)) ++i;
    if (i < scan->getScanSize()) {
      trimmed.emplace(*scan);
      for (; i < trimmed->getScanSize(); ++i)
        if (farOrBad(i)) trimmed->setScanRangeValidity(i, false);
      scored = &*trimmed;
    }
  }
  if (method == lmConsensus || method == lmMeanInformation) {
    // Consensus reads the cell of every valid end point, and MI "inserts" the scan into a copy of
    // the view that MRPT does not grow for it: the view must hold all the scan reaches.
    double r = 0;
    for (std::size_t i = 0; i < scored->getScanSize(); ++i)
      if (scored->getScanRangeValidity(i)) r = std::max<double>(r, scored->getScanRange(i));
    if (method == lmMeanInformation && insertionOptions.considerInvalidRangesAsFreeSpace)
      r = std::max<double>(r, std::min<double>(scored->maxRange > 0.0f ? scored->maxRange : 0.0, insertionOptions.maxDistanceInsertion));
    r += std::hypot(scan->sensorPose.x(), scan->sensorPose.y()) + 1.0;
    need = std::array<double, 4>{pose.x() - r, pose.y() - r, pose.x() + r, pose.y() + r};
    // A pose whose scan cannot reach the map's cells is left to the native path: growing the
    // view there would cost memory without bound (a particle flung kilometres away).
    const Box kb = map_.keyBounds();
    if (kb.isEmpty()) return std::nullopt;
    const Eigen::Vector3d lo = map_.lattice().boxMin(kb), hi = map_.lattice().boxMax(kb);
    if ((*need)[0] < lo.x() - r || (*need)[1] < lo.y() - r || (*need)[2] > hi.x() + r || (*need)[3] > hi.y() + r)
      return std::nullopt;
  }
  // The likelihood field on the view's shared tiles where they stand for it: no view rebuilt
  // after each scan, terms kept across scans away from what the scan changed.
  if (method == lmLikelihoodField_Thrun)
    if (const std::optional<double> l = tilesLikelihood(*scan, pose)) return l;
  const auto v = gridViewShared(need ? need->data() : nullptr);
  std::lock_guard<std::mutex> lk(v->mutex);
  v->setOptions(likelihoodOptions, insertionOptions);
  if (method == lmMeanInformation) {
    // MRPT's MI "inserts" the scan counting information, but its scan insertion writes (and may
    // resize) the grid all the same: run it on a copy, so that the view stays the map's.
    GridView::Grid scratch = v->grid;
    return scratch.computeObservationLikelihood(*scored, pose);
  }
  // The stock grid's likelihood field, its terms and their logarithms kept per cell.
  if (method == lmLikelihoodField_Thrun && v->grid.genericMapParams.enableObservationLikelihood)
    return v->field.scanLogLikelihood(v->grid, *scan, pose);
  // Consensus as rtreeGridMap2D scores it (one implementation): the view holds every end point,
  // so this is MRPT's value; the bounds check stands should it not.
  if (method == lmConsensus && v->grid.genericMapParams.enableObservationLikelihood)
    if (const std::optional<double> l = boundedConsensusLikelihood(v->grid, *scored, mrpt::poses::CPose2D(pose))) return *l;
  return v->grid.computeObservationLikelihood(*scored, pose);
}

// ---- the likelihood field on the 2D view's copy-on-write tiles --------------------------------
//
// The tiles stand for the view where the view is exactly the grid the scans were stepped in:
// the mrpt_grid preset, a grid frame, every known cell in its layer, and the layer inside the
// view's height band (or no cell yet: the stock grid's empty grid of its creation extent). Then
// a column's view cell is its layer cell, and a grid scan's steps (GridScanUpdate) say every
// cell it changed. Anything else that changes the map drops the tiles (notifyMapChanged); they
// are made again from the map when next needed.
std::optional<double> CRTreeOccupancyGridMap::tilesLikelihood(const mrpt::obs::CObservation2DRangeScan& scan,
                                                              const mrpt::poses::CPose3D& pose) const {
  if (!insertionOptions.mrptGrid() || frame_.size_x == 0 || frame_.size_y == 0) return std::nullopt;
  // The options as the dense view's grid holds them: its insertion options are MRPT's defaults
  // (the planar and altitude tests read them), its likelihood options ours.
  static const mrpt::maps::COccupancyGridMap2D::TInsertionOptions kGridInsertion;
  const auto likelihood = [&](GridTiles& t) {
    // (Whether the field's options changed: the tiles compare what their terms were kept with.)
    toGridLikelihoodOptions(likelihoodOptions, caches_->tiles_likelihood);
    const FieldGrid g{&kGridInsertion, &caches_->tiles_likelihood, frame_.resolution, frame_.x_min, frame_.y_min,
                      frame_.size_x, frame_.size_y};
    return t.scanLogLikelihood(g, scan, pose);
  };
  {
    std::lock_guard<std::mutex> lk(caches_->mutex);
    if (caches_->tiles) return likelihood(*caches_->tiles);
  }
  const Box kb = map_.keyBounds();
  auto tiles = std::make_unique<GridTiles>(frame_);
  if (!kb.isEmpty()) {
    if (!frame_.has_layer || kb.min.z != frame_.layer || kb.max.z != frame_.layer) return std::nullopt;
    if (!mrpt_grid::layerInBand(frame_, map_.resolution(), gridViewOptions.gridView_minZ, gridViewOptions.gridView_maxZ))
      return std::nullopt;
    // Made from the dense view on the frame, which reads the map as every view does.
    const auto v = gridViewShared(nullptr);
    std::lock_guard<std::mutex> lk(v->mutex);
    const mrpt::maps::COccupancyGridMap2D& g = v->grid;
    if (g.getSizeX() != frame_.size_x || g.getSizeY() != frame_.size_y || g.getXMin() != frame_.x_min ||
        g.getYMin() != frame_.y_min)
      return std::nullopt;  // the view left the frame: not the grid the steps are in
    tiles->loadDense(g.getRawMap().data());
  }
  std::lock_guard<std::mutex> lk(caches_->mutex);
  if (!caches_->tiles) caches_->tiles = std::move(tiles);
  return likelihood(*caches_->tiles);
}

}  // namespace rtog
