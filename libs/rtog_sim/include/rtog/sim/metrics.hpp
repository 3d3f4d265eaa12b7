// Classification figures of an occupancy map against ground truth: precision and recall of
// the occupied and free classes, the ROC curve and its AUC of P(occupied), and how well the
// probabilities are calibrated (Brier score, negative log-likelihood, expected calibration error
// and the reliability diagram's bins).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace rtog::sim {

/// What a map says about a cell.
enum class Predicted : std::uint8_t { Unknown, Free, Occupied };

struct ClassMetrics {
  std::size_t cells = 0;                          ///< evaluated cells
  std::size_t truth_occupied = 0, truth_free = 0;
  std::size_t pred_occupied = 0, pred_free = 0, unknown = 0;
  std::size_t tp_occupied = 0, tp_free = 0;       ///< predicted class equals truth
  double precision_occupied = 0, recall_occupied = 0, precision_free = 0, recall_free = 0;
  double auc = 0;                                 ///< area under the ROC curve
  std::vector<std::pair<double, double>> roc;     ///< (false positive rate, true positive rate)
  /// Calibration, over the same cells (unknown ones at the prior 0.5): the mean of (P - truth)^2;
  /// the mean of -ln P(truth) [nats]; and the expected calibration error over kCalibrationBins
  /// equal-width bins of P, sum over bins of (cells in bin / cells) * |mean P - occupied share|.
  double brier = 0, nll = 0, ece = 0;
  struct ReliabilityBin {
    double mean_p = 0, occupied_share = 0;
    std::size_t cells = 0;
  };
  std::vector<ReliabilityBin> reliability;  ///< kCalibrationBins bins of P, [k/n, (k+1)/n)
};

constexpr int kCalibrationBins = 10;

/// Accumulates cells, then computes the figures. Unknown cells count as not predicted for
/// precision/recall and score 0.5 in the ROC (the prior).
class Evaluator {
 public:
  /// `p_occ` is the map's P(occupied) (ignored and taken as 0.5 when `pred` is Unknown).
  void add(double p_occ, Predicted pred, bool truth_occupied);
  ClassMetrics finish() const;

 private:
  ClassMetrics m_;
  std::map<double, std::pair<std::uint64_t, std::uint64_t>> hist_;  // score -> (positives, negatives)
};

}  // namespace rtog::sim
