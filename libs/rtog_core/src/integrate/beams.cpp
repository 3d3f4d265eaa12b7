#include "integrate/beams.hpp"

#include <algorithm>

namespace rtog {

RangeNoiseRule::RangeNoiseRule(const LogOddsModel& model, const InsertParams& ip)
    : hit_(model.hitDelta()),
      miss_(model.missDelta()),
      p_hit_(model.params().prob_hit),
      p_miss_(model.params().prob_miss),
      p0_(model.params().prior),
      l0_(std::log(p0_ / (1.0 - p0_))),
      ip_(ip),
      std_(ip.range_noise_std),
      std_per_meter_(ip.range_noise_std_per_meter),
      cutoff_(ip.range_noise_cutoff),
      tail_(0.5 * std::erfc(cutoff_ / std::sqrt(2.0))),
      mass_(1.0 - 2.0 * tail_) {}

double RangeNoiseRule::cdf(double t, double r, double sigma) const {
  const double u = (t - r) / sigma;
  if (u <= -cutoff_) return 0.0;
  if (u >= cutoff_) return 1.0;
  return std::clamp((0.5 * std::erfc(-u / std::sqrt(2.0)) - tail_) / mass_, 0.0, 1.0);
}

bool RangeNoiseRule::cellDelta(double t_in, double t_out, double r, double sigma, float& delta) const {
  const double behind = cdf(t_in, r, sigma), before = cdf(t_out, r, sigma);
  if (behind >= 1.0) return false;
  if (before <= 0.0) {
    delta = ip_.graded(miss_);
    return true;
  }
  if (behind <= 0.0 && before >= 1.0) {
    delta = ip_.graded(hit_);
    return true;
  }
  const double p = (before - behind) * p_hit_ + (1.0 - before) * p_miss_ + behind * p0_;
  delta = ip_.graded(std::log(p / (1.0 - p)) - l0_);
  return true;
}

}  // namespace rtog
