#include "rtog/sim/metrics.hpp"

#include <algorithm>
#include <cmath>

namespace rtog::sim {

void Evaluator::add(double p_occ, Predicted pred, bool truth) {
  ++m_.cells;
  (truth ? m_.truth_occupied : m_.truth_free) += 1;
  switch (pred) {
    case Predicted::Unknown: ++m_.unknown; p_occ = 0.5; break;
    case Predicted::Free: ++m_.pred_free; m_.tp_free += truth ? 0 : 1; break;
    case Predicted::Occupied: ++m_.pred_occupied; m_.tp_occupied += truth ? 1 : 0; break;
  }
  auto& h = hist_[p_occ];
  (truth ? h.first : h.second) += 1;
}

ClassMetrics Evaluator::finish() const {
  ClassMetrics m = m_;
  auto ratio = [](std::size_t a, std::size_t b) { return b ? static_cast<double>(a) / static_cast<double>(b) : 0.0; };
  m.precision_occupied = ratio(m.tp_occupied, m.pred_occupied);
  m.recall_occupied = ratio(m.tp_occupied, m.truth_occupied);
  m.precision_free = ratio(m.tp_free, m.pred_free);
  m.recall_free = ratio(m.tp_free, m.truth_free);
  // Sweep the threshold from the highest score down; equal scores move together (a diagonal
  // segment), which makes the trapezoid area the Mann-Whitney statistic with ties counted 1/2.
  const double P = static_cast<double>(m.truth_occupied), N = static_cast<double>(m.truth_free);
  m.roc.clear();
  m.roc.emplace_back(0.0, 0.0);
  double tp = 0, fp = 0, area = 0;
  for (auto it = hist_.rbegin(); it != hist_.rend(); ++it) {
    const double tp1 = tp + static_cast<double>(it->second.first), fp1 = fp + static_cast<double>(it->second.second);
    area += (fp1 - fp) * (tp + tp1) * 0.5;
    tp = tp1;
    fp = fp1;
    m.roc.emplace_back(N > 0 ? fp / N : 0.0, P > 0 ? tp / P : 0.0);
  }
  m.auc = (P > 0 && N > 0) ? area / (P * N) : 0.0;
  // Calibration from the same histogram. P is kept off 0 and 1 by 1e-12 for the logarithm: every
  // map here clamps its probabilities far inside that.
  m.reliability.assign(kCalibrationBins, {});
  std::vector<double> sum_p(kCalibrationBins, 0.0), occupied(kCalibrationBins, 0.0);
  double brier = 0, nll = 0;
  for (const auto& [p, counts] : hist_) {
    const double pos = static_cast<double>(counts.first), neg = static_cast<double>(counts.second);
    const double q = std::clamp(p, 1e-12, 1.0 - 1e-12);
    brier += pos * (1 - p) * (1 - p) + neg * p * p;
    nll -= pos * std::log(q) + neg * std::log(1 - q);
    const int b = std::clamp(static_cast<int>(p * kCalibrationBins), 0, kCalibrationBins - 1);
    sum_p[b] += p * (pos + neg);
    occupied[b] += pos;
    m.reliability[b].cells += counts.first + counts.second;
  }
  const double cells = static_cast<double>(m.cells);
  if (cells > 0) {
    m.brier = brier / cells;
    m.nll = nll / cells;
    for (int b = 0; b < kCalibrationBins; ++b) {
      auto& bin = m.reliability[b];
      if (bin.cells == 0) continue;
      const double n = static_cast<double>(bin.cells);
      bin.mean_p = sum_p[b] / n;
      bin.occupied_share = occupied[b] / n;
      m.ece += n / cells * std::abs(bin.mean_p - bin.occupied_share);
    }
  }
  return m;
}

}  // namespace rtog::sim
