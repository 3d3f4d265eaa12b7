#include "integrate/beams.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace rtog {
namespace {

/// The standard normal distribution function on a table (linear between 8192 intervals over
/// [-10, 10], within 2e-7 of erfc's), made once per process: a scan's band cells take two values
/// of it each, and erfc's cost was most of the range-noise model's.
class NormalCdf {
 public:
  NormalCdf() {
    for (int i = 0; i <= kN; ++i) v_[static_cast<std::size_t>(i)] = 0.5 * std::erfc(-(-kSpan + i * kH) / std::sqrt(2.0));
  }
  double operator()(double u) const {
    if (!(u > -kSpan)) return 0.0;
    if (!(u < kSpan)) return 1.0;
    const double x = (u + kSpan) * (1.0 / kH);
    const auto i = static_cast<std::size_t>(x);
    const double f = x - static_cast<double>(i);
    return v_[i] + f * (v_[i + 1] - v_[i]);
  }

 private:
  static constexpr double kSpan = 10.0;
  static constexpr int kN = 8192;
  static constexpr double kH = 2.0 * kSpan / kN;
  std::array<double, kN + 2> v_{};  // one past the end: u just below kSpan reads v_[kN + 1] x 0
};

const NormalCdf& normalCdf() {
  static const NormalCdf table;
  return table;
}

}  // namespace

RangeNoiseRule::RangeNoiseRule(const LogOddsModel& model, const InsertParams& ip)
    : hit_(model.hitDelta()),
      miss_(model.missDelta()),
      p_hit_(model.params().prob_hit),
      p_miss_(model.params().prob_miss),
      p0_(model.params().prior),
      l0_(std::log(p0_ / (1.0 - p0_))),
      unit_(ip.graded_unit),
      std_(ip.range_noise_std),
      std_per_meter_(ip.range_noise_std_per_meter),
      cutoff_(ip.range_noise_cutoff),
      // From the same table as cdf()'s values: F is exactly 0 and 1 at the band's edges.
      tail_(normalCdf()(-cutoff_)),
      mass_(normalCdf()(cutoff_) - tail_),
      inv_mass_(1.0 / mass_) {}

double RangeNoiseRule::cdf(double t, double r, double sigma) const {
  // A cell's exit is the next cell's entry along a beam: the value is taken over.
  if (t == last_t_ && r == last_r_ && sigma == last_sigma_) return last_f_;
  if (sigma != inv_of_) inv_of_ = sigma, inv_sigma_ = 1.0 / sigma;  // a beam's cells share its sigma
  const double u = (t - r) * inv_sigma_;
  const double f =
      u <= -cutoff_ ? 0.0 : u >= cutoff_ ? 1.0 : std::clamp((normalCdf()(u) - tail_) * inv_mass_, 0.0, 1.0);
  last_t_ = t, last_r_ = r, last_sigma_ = sigma, last_f_ = f;
  return f;
}

bool RangeNoiseRule::cellDelta(double t_in, double t_out, double r, double sigma, float& delta) const {
  const double behind = cdf(t_in, r, sigma), before = cdf(t_out, r, sigma);
  if (behind >= 1.0) return false;
  if (before <= 0.0) {
    delta = InsertParams::gradedChange(miss_, unit_);
    return true;
  }
  if (behind <= 0.0 && before >= 1.0) {
    delta = InsertParams::gradedChange(hit_, unit_);
    return true;
  }
  const double p = (before - behind) * p_hit_ + (1.0 - before) * p_miss_ + behind * p0_;
  // In single precision, the precision of the stored change (and half the cost of the double log).
  delta = InsertParams::gradedChange(double{std::log(static_cast<float>(p / (1.0 - p)))} - l0_, unit_);
  return true;
}

}  // namespace rtog
