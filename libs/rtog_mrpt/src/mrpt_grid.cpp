// The mrpt_grid preset's mirror of COccupancyGridMap2D (see mrpt_grid.hpp). Built with
// -ffp-contract=off: a fused multiply-add would round where the grid's arithmetic does not.
#include "mrpt_grid.hpp"
#include "archive_read.hpp"
#include "options_check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/poses/CPose2D.h>

namespace rtog::mrpt_grid {

using mrpt::maps::COccupancyGridMap2D;

Steps stepsOf(const CRTreeOccupancyGridMap::TInsertionOptions& o) {
  // As COccupancyGridMap2D::internal_insertObservation: 0 means "as maxOccupancyUpdateCertainty",
  // MRPT's own int8 quantization (p2l), every step at least 1, the occupied one three times.
  const float occ = o.maxOccupancyUpdateCertainty;
  const float free = o.maxFreenessUpdateCertainty == 0.0f ? occ : o.maxFreenessUpdateCertainty;
  const float noecho = o.maxFreenessInvalidRanges == 0.0f ? occ : o.maxFreenessInvalidRanges;
  Steps s;
  s.free = std::max<int>(1, COccupancyGridMap2D::p2l(free));
  s.noecho = std::max<int>(1, COccupancyGridMap2D::p2l(noecho));
  s.occupied = 3 * std::max<int>(1, COccupancyGridMap2D::p2l(occ));
  return s;
}

StepRule stepRule(const Steps& s) {
  constexpr int kMax = 127;  // int8 cells saturate at -127 / 127
  StepRule r;
  const auto fr = static_cast<std::size_t>(StepKind::Free), ne = static_cast<std::size_t>(StepKind::FreeNoEcho),
             oc = static_cast<std::size_t>(StepKind::Occupied);
  // A cell steps towards free while below 127 - the larger free step, else becomes 127 (free);
  // towards occupied while above -127 + the occupied step, else becomes -127. In rtog's values
  // (-cell / 16) the signs flip.
  const float free_limit = valueOfCell(kMax - std::max(s.free, s.noecho));
  r.delta[fr] = valueOfCell(s.free);
  r.delta[ne] = valueOfCell(s.noecho);
  r.limit[fr] = r.limit[ne] = free_limit;
  r.bound[fr] = r.bound[ne] = valueOfCell(kMax);
  r.delta[oc] = valueOfCell(-s.occupied);
  r.limit[oc] = valueOfCell(-kMax + s.occupied);
  r.bound[oc] = valueOfCell(-kMax);
  return r;
}

LogOddsParams logOddsParams(const Steps& s, double occupiedThreshold) {
  LogOddsParams p;
  p.prob_hit = probability(s.occupied / 16.0);
  p.prob_miss = probability(-s.free / 16.0);
  p.clamp_min = probability(-127 / 16.0);
  p.clamp_max = probability(127 / 16.0);
  p.occupied_threshold = occupiedThreshold;
  p.prior = 0.5;
  return p;
}

int cellOfValue(float v) { return static_cast<int>(std::lround(-v * 16.0f)); }

float stepLimit(StepKind kind, int size, const Steps& whole) {
  if (kind == StepKind::Occupied) return valueOfCell(-127 + size);
  const int whole_size = kind == StepKind::Free ? whole.free : whole.noecho;
  return valueOfCell(size == whole_size ? 127 - std::max(whole.free, whole.noecho) : 127 - size);
}

namespace {

/// mrpt::round, which the grid's geometry uses: to nearest, ties to even (lrint in the default
/// rounding mode), not std::round's ties away from zero. At 0.08 m a grown edge of -25 m is
/// -312.5 cells: the stock grid takes -312.
float mrptRound(float v) { return std::nearbyint(v); }

/// The extent and cell counts of a frame of f.resolution, as COccupancyGridMap2D computes them.
void setCells(TGridFrame2D& f, float xmin, float xmax, float ymin, float ymax) {
  const float sx = mrptRound((xmax - xmin) / f.resolution), sy = mrptRound((ymax - ymin) / f.resolution);
  // (Checked before the casts, which a non-finite or huge extent would make undefined; each side
  // too, as a side of 0 cells makes any other side's product small.)
  const double cap = double(archive::kMaxGridCells);
  if (!(sx >= 0.0f && sy >= 0.0f && double{sx} <= cap && double{sy} <= cap && double{sx} * double{sy} <= cap))
    throw std::invalid_argument("rtog mrpt_grid: a grid of more than 2^31 cells (COccupancyGridMap2D indexes its "
                                "cells with an int)");
  f.x_min = xmin, f.x_max = xmax, f.y_min = ymin, f.y_max = ymax;
  f.size_x = static_cast<std::uint32_t>(sx);
  f.size_y = static_cast<std::uint32_t>(sy);
}

}  // namespace

void setSize(TGridFrame2D& f, float xmin, float xmax, float ymin, float ymax, float res) {
  if (!(res > 0.0f) || !(xmax > xmin) || !(ymax > ymin))
    throw std::invalid_argument("rtog mrpt_grid: a grid needs resolution > 0, max_x > min_x and max_y > min_y");
  xmin = res * mrptRound(xmin / res);
  ymin = res * mrptRound(ymin / res);
  xmax = res * mrptRound(xmax / res);
  ymax = res * mrptRound(ymax / res);
  TGridFrame2D g = f;  // f as it was if the size is refused
  g.resolution = res;
  setCells(g, xmin, xmax, ymin, ymax);
  f = g;
}

void resize(TGridFrame2D& f, float nx0, float nx1, float ny0, float ny1) {
  if (nx0 > nx1 || ny0 > ny1) return;  // the grid ignores such a call too
  if (nx0 >= f.x_min && ny0 >= f.y_min && nx1 <= f.x_max && ny1 <= f.y_max) return;
  if (nx0 < f.x_min) nx0 = std::floor(nx0 - 4);
  if (nx1 > f.x_max) nx1 = std::ceil(nx1 + 4);
  if (ny0 < f.y_min) ny0 = std::floor(ny0 - 4);
  if (ny1 > f.y_max) ny1 = std::ceil(ny1 + 4);
  nx0 = std::min(nx0, f.x_min);
  nx1 = std::max(nx1, f.x_max);
  ny0 = std::min(ny0, f.y_min);
  ny1 = std::max(ny1, f.y_max);
  const float res = f.resolution;
  const auto snap = [res](float& v) {
    if (std::fabs(v / res - mrptRound(v / res)) > 0.05f) v = res * mrptRound(v / res);
  };
  snap(nx0), snap(ny0), snap(nx1), snap(ny1);
  setCells(f, nx0, nx1, ny0, ny1);
}

void checkFrame(const TGridFrame2D& f, double resolution) {
  if (f.size_x == 0 && f.size_y == 0 && !f.has_layer) return;
  const auto bad = [](const std::string& why) {
    throw std::runtime_error("rtog::CRTreeOccupancyGridMap: corrupt stream (grid frame: " + why + ")");
  };
  try {
    checkGridExtent("grid frame", f.x_min, f.x_max, f.y_min, f.y_max);
  } catch (const std::invalid_argument& e) {
    bad(e.what());
  }
  if (f.resolution != static_cast<float>(resolution)) bad("its resolution is not the map's");
  // As setSize() and resize() compute the sizes (within a cell: the extent is rounded there).
  const float nx = (f.x_max - f.x_min) / f.resolution, ny = (f.y_max - f.y_min) / f.resolution;
  if (!(std::fabs(nx - static_cast<float>(f.size_x)) <= 1.0f && std::fabs(ny - static_cast<float>(f.size_y)) <= 1.0f))
    bad("its size " + std::to_string(f.size_x) + " x " + std::to_string(f.size_y) + " does not match its extent");
  if (std::uint64_t{f.size_x} * f.size_y > archive::kMaxGridCells) bad("more cells than a 2D grid can index");
  if (f.has_layer && !(f.layer >= kKeyMin && f.layer <= kKeyMax)) bad("its layer is outside the key range");
}

std::int32_t keyOffsetX(const TGridFrame2D& f) {
  return static_cast<std::int32_t>(std::lround(double{f.x_min} / double{f.resolution}));
}
std::int32_t keyOffsetY(const TGridFrame2D& f) {
  return static_cast<std::int32_t>(std::lround(double{f.y_min} / double{f.resolution}));
}

bool planScan(const mrpt::obs::CObservation2DRangeScan& o, const mrpt::poses::CPose3D& robotPose,
              const CRTreeOccupancyGridMap::TInsertionOptions& opts, const TGridFrame2D& f, ScanPlan& plan) {
  const mrpt::poses::CPose3D sensor = robotPose + o.sensorPose;
  for (const double v : {sensor.x(), sensor.y(), sensor.z(), sensor.yaw(), sensor.pitch(), sensor.roll()})
    if (!std::isfinite(v)) throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: non-finite sensor pose");
  if (!o.isPlanarScan(opts.horizontalTolerance)) return false;
  // A NaN or infinite aperture makes every beam angle NaN, and the raster would cast NaN cells
  // to int (found by rtog_fuzz_insert).
  if (!std::isfinite(o.aperture))
    throw std::invalid_argument("rtog::CRTreeOccupancyGridMap: non-finite scan aperture");
  if (opts.useMapAltitude && std::fabs(opts.mapAltitude - sensor.z()) > 0.001) return false;
  const mrpt::poses::CPose2D laser(sensor);
  const bool bottomwards = sensor.getHomogeneousMatrixVal<mrpt::math::CMatrixDouble44>()(2, 2) < 0;
  const int N = static_cast<int>(o.getScanSize());
  const int K = opts.decimation;
  const std::size_t n = o.getScanSize();
  plan.px = static_cast<float>(laser.x());
  plan.py = static_cast<float>(laser.y());
  plan.xs.assign(n, 0.0f);
  plan.ys.assign(n, 0.0f);
  plan.non_finite = 0;
  float A, dAK;
  if (o.rightToLeft ^ bottomwards) {
    A = static_cast<float>(laser.phi() - 0.5f * o.aperture);
    dAK = K * o.aperture / N;
  } else {
    A = static_cast<float>(laser.phi() + 0.5f * o.aperture);
    dAK = -K * o.aperture / N;
  }
  const float maxd = opts.maxDistanceInsertion;
  float last_valid = maxd;
  float x0 = std::numeric_limits<float>::max(), x1 = -x0, y0 = x0, y1 = -x0;
  for (std::size_t i = 0; i < n; i += static_cast<std::size_t>(K)) {
    float& x = plan.xs[i];
    float& y = plan.ys[i];
    if (o.getScanRangeValidity(i)) {
      const float r = o.getScanRange(i);
      if (std::isnan(r)) ++plan.non_finite;  // traced as the grid does: free up to maxDistanceInsertion
      const float R = std::min(maxd, r);
      x = plan.px + std::cos(A) * R;
      y = plan.py + std::sin(A) * R;
      last_valid = r;
    } else if (opts.considerInvalidRangesAsFreeSpace) {
      const float R = std::min(maxd, 0.5f * last_valid);
      x = plan.px + std::cos(A) * R;
      y = plan.py + std::sin(A) * R;
    } else {
      x = plan.px;
      y = plan.py;
    }
    A += dAK;
    x1 = std::max(x1, x), x0 = std::min(x0, x);
    y1 = std::max(y1, y), y0 = std::min(y0, y);
  }
  growRect(f, x0, x1, y0, y1, plan.grow);
  const double reach = std::ldexp(1.0, kKeyBits - 2) * f.resolution;
  // The sensor too: a scan without usable beams does not grow the grid, and the raster would
  // cast the sensor's cell beyond int (found by rtog_fuzz_insert).
  for (const float p : {plan.px, plan.py})
    if (!(std::fabs(p) < reach))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: a 2D scan taken at " + std::to_string(p) +
                              " m, beyond the key range (+-" + std::to_string(reach) + " m)");
  return true;
}

void growRect(const TGridFrame2D& f, float x0, float x1, float y0, float y1, float grow[4]) {
  // The grid grows by 2 m (and resizeGrid's 4 m more) where a point comes within 15 cells of its border.
  const float margin = 15 * f.resolution;
  grow[1] = x1 > f.x_max - margin ? x1 + 2 * margin : f.x_max;
  grow[0] = x0 < f.x_min + margin ? x0 - 2 : f.x_min;
  grow[3] = y1 > f.y_max - margin ? y1 + 2 * margin : f.y_max;
  grow[2] = y0 < f.y_min + margin ? y0 - 2 : f.y_min;
  // Beyond the key range no cell has a key: refuse before the grid's geometry grows there.
  const double reach = std::ldexp(1.0, kKeyBits - 2) * f.resolution;
  for (int i = 0; i < 4; ++i)
    if (!(std::fabs(grow[i]) < reach))
      throw std::out_of_range("rtog::CRTreeOccupancyGridMap: an observation reaches " + std::to_string(grow[i]) +
                              " m, beyond the key range (+-" + std::to_string(reach) + " m)");
}

std::size_t invalidNotFree(const mrpt::obs::CObservation2DRangeScan& o, const CRTreeOccupancyGridMap::TInsertionOptions& opts) {
  std::size_t invalid = 0;
  if (!opts.considerInvalidRangesAsFreeSpace)
    for (std::size_t i = 0; i < o.getScanSize(); i += opts.decimation) invalid += o.getScanRangeValidity(i) ? 0 : 1;
  return invalid;
}

void traceScan(const mrpt::obs::CObservation2DRangeScan& o, const ScanPlan& plan,
               const CRTreeOccupancyGridMap::TInsertionOptions& opts, const TGridFrame2D& f,
               std::vector<OccupancyMap::StepRun>& runs, InsertStats& stats, std::vector<float>* ranges,
               const Box& clip) {
  constexpr int kFrBits = OccupancyMap::kRunFracBits;  // the grid's raster: 1/512 cell
  // The raster's cells stay within a cell and the rounding of the step, times the steps, of the
  // segment from the start cell to the end cell: with that margin, a box that misses the clip
  // box holds every cell of the beam.
  const auto missesClip = [&clip](const OccupancyMap::StepRun& r, int nsteps) {
    if (clip.isEmpty()) return false;
    const std::int64_t m = nsteps / 1024 + 2;
    const std::int64_t x0 = std::min(r.x, r.end_x) - m, x1 = std::max(r.x, r.end_x) + m;
    const std::int64_t y0 = std::min(r.y, r.end_y) - m, y1 = std::max(r.y, r.end_y) + m;
    return x1 < clip.min.x || x0 > clip.max.x || y1 < clip.min.y || y0 > clip.max.y;
  };
  const std::size_t n = o.getScanSize();
  const auto K = static_cast<std::size_t>(opts.decimation);
  const bool trace_free = opts.sensorModel != "endpoint";
  const float maxd = opts.maxDistanceInsertion;
  const std::int32_t ox = keyOffsetX(f), oy = keyOffsetY(f);
  const int cx0 = x2idx(f, plan.px), cy0 = y2idx(f, plan.py);
  runs.clear();
  runs.reserve(n / K + 1);
  if (ranges) ranges->clear();
  for (std::size_t i = 0; i < n; i += K) {
    const bool valid = o.getScanRangeValidity(i);
    if (!valid && !opts.considerInvalidRangesAsFreeSpace) {
      ++stats.rays_truncated;
      continue;
    }
    const int tx = x2idx(f, plan.xs[i]), ty = y2idx(f, plan.ys[i]);
    if (static_cast<unsigned>(tx) >= f.size_x || static_cast<unsigned>(ty) >= f.size_y)
      throw std::logic_error("rtog mrpt_grid: a beam's end lies outside the grown grid");
    const int ax = tx - cx0, ay = ty - cy0;
    const int nsteps = std::max(std::abs(ax), std::abs(ay));
    if (nsteps == 0) {  // the grid marks nothing for a beam that ends in its start cell
      ++stats.skipped_zero_length;
      continue;
    }
    OccupancyMap::StepRun r{};
    r.x = cx0 + ox, r.y = cy0 + oy;
    r.kind = valid ? StepKind::Free : StepKind::FreeNoEcho;
    if (trace_free) {
      const float inv = 1.0f / nsteps;
      r.dx = static_cast<int>((ax < 0 ? -1 : +1) * std::round((std::abs(ax) << kFrBits) * inv));
      r.dy = static_cast<int>((ay < 0 ? -1 : +1) * std::round((std::abs(ay) << kFrBits) * inv));
      r.count = static_cast<std::uint32_t>(nsteps);
    }
    r.end = valid && o.getScanRange(i) < maxd;
    r.end_x = tx + ox, r.end_y = ty + oy;
    ++(r.end ? stats.rays_hit : stats.rays_truncated);
    if ((r.count > 0 || r.end) && !missesClip(r, nsteps)) {
      runs.push_back(r);
      if (ranges) ranges->push_back(r.end ? o.getScanRange(i) : 0.0f);
    }
  }
}

}  // namespace rtog::mrpt_grid
