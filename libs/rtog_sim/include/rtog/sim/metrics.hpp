// Classification figures of an occupancy map against ground truth: precision and recall of
// the occupied and free classes, and the ROC curve and its AUC of P(occupied).
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
};

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
