#include "likelihood_field_2d.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <mrpt/core/round.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/poses/CPose2D.h>

namespace rtog {
namespace {

// COccupancyGridMap2D::x2idx / y2idx, without its float-to-int cast of a point beyond the int
// range (undefined behaviour): such a point is outside the grid, -1, as x86 turns the cast
// into INT_MIN, which the stock grid then counts outside too.
int cellIndex(double v, double lo, double res) {
  const double i = (v - lo) / res;
  return i > -2147483648.0 && i < 2147483647.0 ? static_cast<int>(i) : -1;
}

using Grid = mrpt::maps::COccupancyGridMap2D;

/// The field's constants in the precision the stock grid computes them in (floats where its
/// options are floats), so that every term is the same number.
struct Field {
  float zRandomTerm, zHit, q;  // q = -1 / (2 stdHit^2)
  double maxCorrDistSq;         // a float square, widened
  double unitsPerSqMetre;       // squared distances counted in (cell / 10)^2
  unsigned capUnits;            // the search's cap in those units
  int window;                   // cells searched either side
  bool squareDist;
  float threshold;              // a cell below it counts as occupied (P(occupied) > 0.5)
};

Field fieldOf(const Grid& g) {
  const auto& o = g.likelihoodOptions;
  Field f{};
  f.zRandomTerm = o.LF_zRandom / o.LF_maxRange;
  f.zHit = o.LF_zHit;
  f.q = -0.5f / (o.LF_stdHit * o.LF_stdHit);
  f.maxCorrDistSq = o.LF_maxCorrsDistance * o.LF_maxCorrsDistance;
  const double res = g.getResolution();
  f.unitsPerSqMetre = 100 / (res * res);
  f.capUnits = static_cast<unsigned>(mrpt::round(f.maxCorrDistSq * f.unitsPerSqMetre));
  f.window = static_cast<int>(std::ceil(o.LF_maxCorrsDistance / g.getResolution()));
  f.squareDist = o.LF_useSquareDist;
  f.threshold = Grid::p2l(0.5f);
  return f;
}

/// The term of a point in cell (cx, cy), inside the grid's border: the mixture at the distance of
/// the nearest occupied cell within the window (capped).
double termAt(const Grid& g, const Field& f, int cx, int cy) {
  const int sx = static_cast<int>(g.getSizeX()), sy = static_cast<int>(g.getSizeY());
  const int x0 = std::max(0, cx - f.window), x1 = std::min(sx - 1, cx + f.window);
  const int y0 = std::max(0, cy - f.window), y1 = std::min(sy - 1, cy + f.window);
  const auto& cells = g.getRawMap();
  unsigned best = f.capUnits;
  for (int y = y0; y <= y1; ++y) {
    const auto* row = cells.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(sx);
    const auto dy = static_cast<unsigned>(10 * (y - cy));
    const unsigned dy2 = dy * dy;
    for (int x = x0; x <= x1; ++x)
      if (row[x] < f.threshold) {
        const auto dx = static_cast<unsigned>(10 * (x - cx));  // squared modulo 2^32: the same
        best = std::min(best, dx * dx + dy2);
      }
  }
  float dist = static_cast<float>(best * (1.0 / f.unitsPerSqMetre));
  if (f.squareDist) dist *= dist;
  return f.zRandomTerm + f.zHit * std::exp(f.q * dist);  // in floats, as the stock grid
}

}  // namespace

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
                                            const mrpt::poses::CPose3D& pose3d) {
  // As COccupancyGridMap2D::internal_computeObservationLikelihood and its likelihood field.
  const auto& io = g.insertionOptions;
  if (!scan.isPlanarScan(io.horizontalTolerance)) return -10;
  if (io.useMapAltitude && std::fabs(io.mapAltitude - scan.sensorPose.z()) > 0.01) return -10;
  const mrpt::poses::CPose2D pose(pose3d);
  mrpt::maps::CPointsMap::TInsertionOptions opts;
  opts.minDistBetweenLaserPoints = g.getResolution() * 0.5f;
  opts.isPlanarMap = true;
  opts.horizontalTolerance = io.horizontalTolerance;
  const mrpt::maps::CPointsMap* pts = scan.buildAuxPointsMap<mrpt::maps::CPointsMap>(&opts);
  const std::size_t n = pts ? pts->size() : 0;
  if (n == 0) return -100;
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
  const Field f = fieldOf(g);
  const double outside = f.zRandomTerm + f.zHit * std::exp(f.q * f.maxCorrDistSq);  // in doubles
  const double outside_value = logs ? std::log(outside) : outside;
  const std::size_t step = n < 10 ? 1 : static_cast<std::size_t>(std::max<std::uint32_t>(1u, lo.LF_decimation));
  double s, c;
  ::sincos(pose.phi(), &s, &c);
  const auto& xs = pts->getPointsBufferRef_x();
  const auto& ys = pts->getPointsBufferRef_y();
  const unsigned last_x = g.getSizeX() - 1, last_y = g.getSizeY() - 1;
  double sum = 0;
  std::size_t m = 0;
  for (std::size_t j = 0; j < n; j += step, ++m) {
    const double lx = xs[j], ly = ys[j];
    const int cx = cellIndex(pose.x() + lx * c - ly * s, g.getXMin(), g.getResolution());
    const int cy = cellIndex(pose.y() + lx * s + ly * c, g.getYMin(), g.getResolution());
    // The grid's last row and column count as outside, as in the stock grid.
    if (static_cast<unsigned>(cx) >= last_x || static_cast<unsigned>(cy) >= last_y) {
      sum += outside_value;
      continue;
    }
    const std::size_t at = static_cast<std::size_t>(cx) + static_cast<std::size_t>(cy) * g.getSizeX();
    double* kept = keep ? &term(at) : nullptr;
    double v = kept ? *kept : std::numeric_limits<double>::quiet_NaN();
    if (std::isnan(v)) {
      const double t = termAt(g, f, cx, cy);
      v = logs ? std::log(t) : t;
      if (kept) *kept = v;
    }
    sum += v;
  }
  return logs ? sum : std::log(sum / static_cast<double>(m));
}

}  // namespace rtog
