// The cone rule of range sensors with a wide beam (rtog/core/cone.hpp, doc/sonar.md).
#include "rtog/core/cone.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "integrate/beams.hpp"
#include "integrate/cone_integrator.hpp"
#include "integrate/graded_scan.hpp"
#include "integrate/insert_scratch.hpp"
#include "storage/map_store.hpp"
#include "rtog/core/ray_traversal.hpp"

namespace rtog {

const char* toString(ConeWeighting w) { return w == ConeWeighting::Elfes ? "elfes" : "uniform"; }

ConeWeighting coneWeightingFromString(const std::string& s) {
  if (s == "uniform") return ConeWeighting::Uniform;
  if (s == "elfes") return ConeWeighting::Elfes;
  throw std::invalid_argument("cone weighting must be uniform or elfes, got '" + s + "'");
}

void coneCells(const Lattice& lattice, const ConeReading& r, ConeWeighting w, std::vector<ConeCell>& out,
               std::int32_t* layer) {
  constexpr double kPi = 3.14159265358979323846;
  if (!(std::isfinite(r.range) && r.range > 0.0))
    throw std::invalid_argument("cone reading: the range must be positive and finite");
  if (!(r.aperture >= 0.0 && r.aperture <= kPi))
    throw std::invalid_argument("cone reading: the aperture must be in [0, pi] rad");
  if (!r.origin.allFinite() || !std::isfinite(r.yaw))
    throw std::invalid_argument("cone reading: the origin and the yaw must be finite");
  const Eigen::Vector3d dir(std::cos(r.yaw), std::sin(r.yaw), 0.0);
  const Eigen::Vector3d end = r.origin + r.range * dir;
  const Key ok = lattice.key(r.origin), ek = lattice.key(end);  // throw before anything is written
  if (layer) *layer = ok.z;
  out.clear();

  // The sector's bounding box in cells: the origin, the arc's two ends and every axis direction
  // (0, 90, 180, 270 deg) inside the aperture, at the arc's outer reach, one cell of margin.
  const Eigen::Vector3d o = lattice.toLattice(r.origin);
  const double reach = lattice.toLattice(r.range) + 0.5, half = 0.5 * r.aperture;
  double x0 = std::min(o.x(), static_cast<double>(ek.x)), x1 = std::max(o.x(), ek.x + 1.0);
  double y0 = std::min(o.y(), static_cast<double>(ek.y)), y1 = std::max(o.y(), ek.y + 1.0);
  auto grow = [&](double a) {
    x0 = std::min(x0, o.x() + reach * std::cos(a));
    x1 = std::max(x1, o.x() + reach * std::cos(a));
    y0 = std::min(y0, o.y() + reach * std::sin(a));
    y1 = std::max(y1, o.y() + reach * std::sin(a));
  };
  if (half > 0.0) {
    grow(r.yaw - half);
    grow(r.yaw + half);
    for (int q = -4; q <= 4; ++q) {
      const double a = q * 0.5 * kPi;
      if (std::remainder(a - r.yaw, 2.0 * kPi) >= -half && std::remainder(a - r.yaw, 2.0 * kPi) <= half) grow(a);
    }
  }
  // Clipped to the key range: cells beyond it cannot be stored (the axis's cells all have keys).
  auto clip = [](double v) { return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(v)), kKeyMin, kKeyMax); };
  const std::int64_t bx0 = clip(x0 - 1.0), bx1 = clip(x1 + 1.0), by0 = clip(y0 - 1.0), by1 = clip(y1 + 1.0);
  const auto nx = static_cast<std::size_t>(bx1 - bx0 + 1), ny = static_cast<std::size_t>(by1 - by0 + 1);
  // Per cell of the box: the largest free and occupied weight claimed (0: none).
  std::vector<float> free_w(nx * ny, 0.0f), occ_w(nx * ny, 0.0f);
  auto at = [&](std::int64_t x, std::int64_t y) { return static_cast<std::size_t>(y - by0) * nx + static_cast<std::size_t>(x - bx0); };

  if (half > 0.0) {
    const double inner = reach - 1.0;  // range - half a cell
    for (std::int64_t y = by0; y <= by1; ++y)
      for (std::int64_t x = bx0; x <= bx1; ++x) {
        const double vx = x + 0.5 - o.x(), vy = y + 0.5 - o.y();
        const double d = std::hypot(vx, vy);
        if (d >= reach) continue;
        const double theta = d > 0.0 ? std::atan2(dir.x() * vy - dir.y() * vx, dir.x() * vx + dir.y() * vy) : 0.0;
        if (std::abs(theta) > half) continue;
        const double t = theta / half;
        const auto wt = static_cast<float>(w == ConeWeighting::Elfes ? 1.0 - t * t : 1.0);
        if (!(wt > 0.0f)) continue;
        if (d < inner) {
          free_w[at(x, y)] = std::max(free_w[at(x, y)], wt);
        } else if (r.hit) {
          occ_w[at(x, y)] = std::max(occ_w[at(x, y)], wt);
        }
      }
  }
  // The axis, as the beam model walks a beam.
  const Eigen::Vector3d to = lattice.toLattice(end);
  if (!(ok == ek))
    traverseRay(o, to, ok, ek, [&](const Key& k) {
      if (!(k == ek)) free_w[at(k.x, k.y)] = 1.0f;
    });
  if (r.hit) occ_w[at(ek.x, ek.y)] = 1.0f;

  const StepKind free_kind = r.hit ? StepKind::Free : StepKind::FreeNoEcho;
  for (std::int64_t y = by0; y <= by1; ++y)
    for (std::int64_t x = bx0; x <= bx1; ++x) {
      const std::size_t i = at(x, y);
      if (occ_w[i] > 0.0f) {
        out.push_back(ConeCell{static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), StepKind::Occupied, occ_w[i]});
      } else if (free_w[i] > 0.0f) {
        out.push_back(ConeCell{static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), free_kind, free_w[i]});
      }
    }
}

UpdateSet ConeIntegrator::trace(const ConeReading* readings, std::size_t n, ConeWeighting w, const InsertParams& ip) {
  ip.validate();
  const MapStore& store = ctx_.store;
  const BeamRules rules(store.lattice, ip);
  // Every reading's cells first, so that a bad one throws before the map changes.
  InsertStats stats;
  std::vector<std::vector<ConeCell>> cells(n);
  std::vector<std::int32_t> layers(n, 0);
  std::vector<bool> traced(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    ConeReading r = readings[i];
    // The axis is a beam: skipped, cut at max_range (no echo then) or bounded as a beam is.
    const Eigen::Vector3d p = r.origin + r.range * Eigen::Vector3d(std::cos(r.yaw), std::sin(r.yaw), 0.0);
    Eigen::Vector3d end;
    Key end_key;
    const std::string which = "insertCones: reading " + std::to_string(i);
    if (!r.origin.allFinite()) throw std::invalid_argument(which + ": the origin is not finite");
    if (!(r.aperture >= 0.0 && r.aperture <= 3.14159265358979323846))
      throw std::invalid_argument(which + ": the aperture must be in [0, pi] rad");
    (void)store.lattice.key(r.origin);  // std::out_of_range for an origin without a key
    // A reading is data: a bad one is a counted skip, as a bad beam is.
    if (!std::isfinite(r.range) || !std::isfinite(r.yaw)) {
      ++stats.skipped_non_finite;
      continue;
    }
    if (!(r.range > 0.0)) {
      ++stats.skipped_zero_length;
      continue;
    }
    const BeamEnd kind = rules.classify(r.origin, p, r.hit, end, end_key);
    if (!BeamRules::count(kind, stats)) continue;
    r.range = std::min(r.range, (end - r.origin).norm());
    r.hit = kind == BeamEnd::Hit;
    coneCells(store.lattice, r, w, cells[i], &layers[i]);
    traced[i] = true;
  }
  const LogOddsModel& model = store.model;
  std::size_t readings_traced = 0;
  for (std::size_t i = 0; i < n; ++i) readings_traced += traced[i];
  std::vector<GradedScan>& g = ctx_.scratch.graded;
  if (g.size() < readings_traced) g.resize(readings_traced);
  UpdateSet set = UpdateSet::nothing(UpdateSet::Kind::Sequence, stats);
  for (std::size_t i = 0; i < n; ++i) {
    if (!traced[i]) continue;
    // Each reading is one measurement: its cells take their change once, readings in order.
    GradedScan& one = g[set.graded.size()];
    one.clear();
    for (const ConeCell& c : cells[i])
      one.mark(Key{c.x, c.y, layers[i]}, c.weight * (c.kind == StepKind::Occupied ? model.hitDelta() : model.missDelta()));
    one.finalize();
    set.graded.push_back(&one);
  }
  return set;
}

}  // namespace rtog
