// The probability mixture of an uncertain placement, the one rule of pose blur (a scan from a
// weighted set of poses) and of fusion under uncertain poses (the estimator seed's "additional
// covariance for registration uncertainty"): a cell takes P = P0 + sum_i w_i (P_i - P0) over the
// placements that say something of it (one that does not adds the prior P0), entered once as
// the change logit(P) - l0.
#pragma once

#include <algorithm>
#include <cmath>

#include "rtog/core/log_odds.hpp"

namespace rtog {

class ProbabilityMixture {
 public:
  explicit ProbabilityMixture(float prior) : l0_(prior), p0_(probability(prior)) {}

  /// w (P_i - P0) of a placement that would change the cell by `delta` (log-odds).
  double term(double w, double delta) const { return w * (probability(double(l0_) + delta) - p0_); }
  /// The change of a cell whose terms sum to `sum`. P lies between the smallest and the largest
  /// P_i, all in (0, 1); the clamp only guards against rounding at the ends.
  float change(double sum) const {
    const double p = std::clamp(p0_ + sum, 1e-12, 1.0 - 1e-12);
    return static_cast<float>(logit(p) - double(l0_));
  }

 private:
  float l0_;
  double p0_;
};

}  // namespace rtog
