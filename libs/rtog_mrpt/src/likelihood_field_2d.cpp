#include "likelihood_field_2d.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <mrpt/core/round.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/poses/CPose2D.h>

namespace rtog {
namespace {

using Grid = mrpt::maps::COccupancyGridMap2D;

/// The field on a dense grid's cells: value(at, logs, term_of) gives the value of cell `at`
/// (row-major), from term_of() (its term, computed) or from what it kept.
template <class Value>
double onDenseGrid(const Grid& g, const mrpt::obs::CObservation2DRangeScan& scan, const mrpt::poses::CPose3D& pose,
                   Value&& value) {
  const FieldConstants f(g.likelihoodOptions, g.getResolution());
  const int sx = static_cast<int>(g.getSizeX()), sy = static_cast<int>(g.getSizeY());
  const auto& raw = g.getRawMap();
  const float below = occupiedBelow();
  const auto row = [&](int y, int x0, int x1, auto&& visit) {
    const auto* r = raw.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(sx);
    for (int x = x0; x <= x1; ++x)
      if (r[x] < below) visit(x);
  };
  const FieldGrid fg{&g.insertionOptions, &g.likelihoodOptions, g.getResolution(), g.getXMin(), g.getYMin(),
                     g.getSizeX(), g.getSizeY()};
  return fieldScanLogLikelihood(fg, f, scan, pose, [&](int cx, int cy, bool lg) {
    return value(static_cast<std::size_t>(cx) + static_cast<std::size_t>(cy) * g.getSizeX(), lg,
                 [&] { return f.termOfBest(f.bestAt(cx, cy, sx, sy, row)); });
  });
}

}  // namespace

FieldConstants::FieldConstants(const Grid::TLikelihoodOptions& o, double res) {
  zRandomTerm = o.LF_zRandom / o.LF_maxRange;
  zHit = o.LF_zHit;
  q = -0.5f / (o.LF_stdHit * o.LF_stdHit);
  maxCorrDistSq = o.LF_maxCorrsDistance * o.LF_maxCorrsDistance;
  unitsPerSqMetre = 100 / (res * res);
  capUnits = static_cast<unsigned>(mrpt::round(maxCorrDistSq * unitsPerSqMetre));
  window = static_cast<int>(std::ceil(o.LF_maxCorrsDistance / res));
  squareDist = o.LF_useSquareDist;
}

float occupiedBelow() { return Grid::p2l(0.5f); }

FieldScan prepareFieldScan(const FieldGrid& g, const FieldConstants& f, const mrpt::obs::CObservation2DRangeScan& scan,
                           const mrpt::poses::CPose3D& pose3d) {
  // As COccupancyGridMap2D::internal_computeObservationLikelihood and its likelihood field.
  FieldScan p{};
  p.decided = std::numeric_limits<double>::quiet_NaN();
  const auto& io = *g.insertion;
  if (!scan.isPlanarScan(io.horizontalTolerance)) return p.decided = -10, p;
  if (io.useMapAltitude && std::fabs(io.mapAltitude - scan.sensorPose.z()) > 0.01) return p.decided = -10, p;
  const mrpt::poses::CPose2D pose(pose3d);
  mrpt::maps::CPointsMap::TInsertionOptions opts;
  opts.minDistBetweenLaserPoints = g.resolution * 0.5f;
  opts.isPlanarMap = true;
  opts.horizontalTolerance = io.horizontalTolerance;
  const mrpt::maps::CPointsMap* pts = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>(&opts);
  p.n = pts ? pts->size() : 0;
  if (p.n == 0) return p.decided = -100, p;
  const auto& lo = *g.likelihood;
  p.logs = !lo.LF_alternateAverageMethod;
  const double outside = f.zRandomTerm + f.zHit * std::exp(f.q * f.maxCorrDistSq);  // in doubles
  p.outside_value = p.logs ? std::log(outside) : outside;
  p.step = p.n < 10 ? 1 : static_cast<std::size_t>(std::max<std::uint32_t>(1u, lo.LF_decimation));
  ::sincos(pose.phi(), &p.s, &p.c);
  p.x = pose.x(), p.y = pose.y();
  p.xs = pts->getPointsBufferRef_x().data();
  p.ys = pts->getPointsBufferRef_y().data();
  return p;
}

double& LikelihoodField2D::term(std::size_t at) {
  auto& page = pages_[at >> kPageBits];
  if (!page) {
    constexpr std::size_t n = std::size_t{1} << kPageBits;
    page.reset(new double[n]);
    std::fill(page.get(), page.get() + n, std::numeric_limits<double>::quiet_NaN());
  }
  return page[at & ((std::size_t{1} << kPageBits) - 1)];
}

double LikelihoodField2D::scanLogLikelihood(const Grid& g, const mrpt::obs::CObservation2DRangeScan& scan,
                                            const mrpt::poses::CPose3D& pose) {
  const auto& lo = g.likelihoodOptions;
  const bool logs = !lo.LF_alternateAverageMethod;
  const bool keep = lo.enableLikelihoodCache;
  const std::size_t cells = std::size_t{g.getSizeX()} * g.getSizeY();
  if (keep && (cells_ != cells || logs_ != logs)) {
    pages_.clear();
    pages_.resize((cells >> kPageBits) + 1);
    cells_ = cells;
    logs_ = logs;
  }
  return onDenseGrid(g, scan, pose, [&](std::size_t at, bool lg, auto&& term_of) {
    double* kept = keep ? &term(at) : nullptr;
    double v = kept ? *kept : std::numeric_limits<double>::quiet_NaN();
    if (std::isnan(v)) {
      const double t = term_of();
      v = lg ? std::log(t) : t;
      if (kept) *kept = v;
    }
    return v;
  });
}

double keptFieldScanLogLikelihood(const Grid& g, std::vector<double>& kept, bool& outdated,
                                  const mrpt::obs::CObservation2DRangeScan& scan, const mrpt::poses::CPose3D& pose) {
  const auto& lo = g.likelihoodOptions;
  const bool keep = lo.enableLikelihoodCache;
  if (keep && outdated) {
    // As MRPT resets it (an empty grid keeps none).
    if (!g.getRawMap().empty())
      kept.assign(g.getRawMap().size(), kTermNotComputed);
    else
      kept.clear();
    outdated = false;
  }
  return onDenseGrid(g, scan, pose, [&](std::size_t at, bool lg, auto&& term_of) {
    double* slot = keep ? &kept[at] : nullptr;
    double t = slot ? *slot : kTermNotComputed;
    if (t == kTermNotComputed) {
      t = term_of();
      if (slot) *slot = t;
    }
    return lg ? std::log(t) : t;
  });
}

}  // namespace rtog
