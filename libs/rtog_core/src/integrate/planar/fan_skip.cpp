#include "integrate/planar/fan_skip.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace rtog {

void fanSkipRuns(PlanarBeam* beams, std::size_t count) {
  // A beam's geometry in cells, unmirrored, from the rounded start point.
  struct Ray {
    double dx, dy, length, inverse_length;
  };
  thread_local std::vector<Ray> rays;
  rays.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const PlanarSegment& s = beams[i].seg;
    const double cell = 1.0 / static_cast<double>(std::int64_t{1} << s.shift);
    const double dx = static_cast<double>(s.sx * s.dx) * cell, dy = static_cast<double>(s.sy * s.dy) * cell;
    const double length = std::sqrt(dx * dx + dy * dy);
    rays[i] = Ray{dx, dy, length, length > 0.0 ? 1.0 / length : 0.0};
    beams[i].skip_runs = 0;
  }
  const auto sameStart = [](const PlanarSegment& a, const PlanarSegment& b) {
    const std::int64_t one = std::int64_t{1} << a.shift;
    const auto ux = [one](const PlanarSegment& s) { return s.sx > 0 ? s.x0 : one - 1 - s.x0; };
    const auto uy = [one](const PlanarSegment& s) { return s.sy > 0 ? s.y0 : one - 1 - s.y0; };
    return a.shift == b.shift && ux(a) == ux(b) && uy(a) == uy(b);
  };
  constexpr double kDiagonal = 1.4142135623730951;
  for (std::size_t i = 1; i < count; ++i) {
    PlanarBeam& beam = beams[i];
    const std::size_t step = i & (~i + 1);  // beams i -/+ step: fewer trailing zero bits than i
    if (!beam.traced || i + step >= count) continue;
    const PlanarBeam &left = beams[i - step], &right = beams[i + step];
    const Ray &a = rays[i - step], &b = rays[i + step], &c = rays[i];
    if (!left.traced || !right.traced || !(a.length > 2.0 && b.length > 2.0 && c.length > 0.0)) continue;
    if (!sameStart(beam.seg, left.seg) || !sameStart(beam.seg, right.seg)) continue;
    // Beam strictly between its neighbours, which are less than half a turn apart: sines of
    // one sign, each well beyond its rounding.
    const auto cross = [](const Ray& u, const Ray& v) { return u.dx * v.dy - u.dy * v.dx; };
    const double ab = cross(a, b), ac = cross(a, c), cb = cross(c, b);
    constexpr double sure = 1e-9;
    const double ab_sure = sure * a.length * b.length, ac_sure = sure * a.length * c.length,
                 cb_sure = sure * c.length * b.length;
    const bool counter_clockwise = ab > ab_sure && ac > ac_sure && cb > cb_sure;
    const bool clockwise = ab < -ab_sure && ac < -ac_sure && cb < -cb_sure;
    if (!counter_clockwise && !clockwise) continue;
    // A unit cell inside the wedge of angle t holds a disc of radius 1/2 whose centre is at
    // least 1 / (2 sin(t/2)) from the apex; a cell nearer crosses a side, inside that side's
    // segment if the segment reaches 2 cells further (its end cell is not free).
    const double cos_t = (a.dx * b.dx + a.dy * b.dy) * a.inverse_length * b.inverse_length;
    const double sin_half = std::sqrt(std::max(1.0 - cos_t, 0.0) / 2.0);
    const double radius = std::min({0.999 / (2.0 * sin_half), a.length - 2.0, b.length - 2.0});
    // The cells of runs before r lie within r / |minor extent| of the beam's length, plus a diagonal.
    const bool rows = beam.seg.nx >= beam.seg.ny;
    const double minor = std::abs(rows ? c.dy : c.dx);
    if (!(radius > kDiagonal)) continue;
    const double runs = std::floor((radius - kDiagonal) * minor * c.inverse_length);
    beam.skip_runs = std::min(static_cast<std::int64_t>(runs), rows ? beam.seg.ny : beam.seg.nx);
  }
}

}  // namespace rtog
