// The range-noise inverse model (doc/range-noise.md): the change a reading with Gaussian range
// error makes to each cell its beam crosses. Public, as every path that rasters beams (the core's
// walks, the mrpt_grid preset's grid rasters) grades its cells by this one rule.
#pragma once

#include <limits>

#include "rtog/core/log_odds.hpp"
#include "rtog/core/params.hpp"

namespace rtog {

/// The range-noise inverse model (doc/range-noise.md). A reading r of a surface at true distance
/// z has p(r | z) = N(r; z, sigma^2); with a flat prior along the beam, z | r is Gaussian about r,
/// taken to lie within cutoff * sigma of it (normalized there). A cell the beam crosses over
/// [t_in, t_out] then holds the surface with probability w_hit = F(t_out) - F(t_in), was passed
/// through (free) with w_pass = 1 - F(t_out), and lies behind the surface, unobserved, with
/// w_behind = F(t_in) (F the distribution function of z | r). By total probability
///   P(occ | r) = w_hit * prob_hit + w_pass * prob_miss + w_behind * prior,
/// entered as l_meas - l0 = logit(P(occ | r)) - l0. A cell wholly before the band takes the
/// model's miss change, one holding the whole band its hit change, exactly.
///
/// Not to be shared between threads (it keeps its last value of F): one object per thread.
class RangeNoiseRule {
 public:
  RangeNoiseRule(const LogOddsModel& model, const InsertParams& ip);

  /// sigma [m] of a reading at `range` [m].
  double sigma(double range) const { return std_ + std_per_meter_ * range; }
  /// How far past the reading the band reaches [m].
  double reach(double sigma) const { return cutoff_ * sigma; }
  /// The change of a cell crossed over [t_in, t_out] (metres from the sensor, t_in <= t_out) for a
  /// reading at r with sigma > 0, rounded to InsertParams::graded_unit; false if the cell lies
  /// wholly behind the band (untouched).
  bool cellDelta(double t_in, double t_out, double r, double sigma, float& delta) const;

 private:
  double cdf(double t, double r, double sigma) const;  // F, 0 below the band, 1 above it

  // cdf()'s last value (a cell's exit is the next one's entry): one rule object per thread.
  mutable double last_t_ = std::numeric_limits<double>::quiet_NaN(), last_r_ = 0.0, last_sigma_ = 0.0, last_f_ = 0.0;
  mutable double inv_of_ = 0.0, inv_sigma_ = 0.0;  // 1 / sigma of the last sigma
  float hit_, miss_;
  double p_hit_, p_miss_, p0_, l0_;
  double unit_;  // InsertParams::graded_unit
  double std_, std_per_meter_, cutoff_, tail_, mass_, inv_mass_;  // tail_ = Phi(-cutoff), mass_ = 1 - 2 tail_
};

}  // namespace rtog
