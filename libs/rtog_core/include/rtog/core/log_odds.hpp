// Log-odds occupancy: the Bayes update l = l_prev + l_meas - l0 with clamping.
#pragma once

#include <algorithm>

#include <cmath>
#include <stdexcept>
#include <string>

namespace rtog {

inline double logit(double p) { return std::log(p / (1.0 - p)); }
inline double probability(double log_odds) { return 1.0 / (1.0 + std::exp(-log_odds)); }

enum class CellState { Unknown, Free, Occupied };
const char* toString(CellState s);

/// Sensor and clamping probabilities. Defaults equal OctoMap's so that maps can be compared.
struct LogOddsParams {
  double prob_hit = 0.7;          ///< P(occupied | beam ended in the cell). (Default: 0.7)
  double prob_miss = 0.4;         ///< P(occupied | beam crossed the cell). (Default: 0.4)
  double clamp_min = 0.1192;      ///< Lower clamping probability µmin. (Default: 0.1192)
  double clamp_max = 0.971;       ///< Upper clamping probability µmax. (Default: 0.971)
  double occupied_threshold = 0.5;///< Cells at or above this probability are occupied. (Default: 0.5)
  double prior = 0.5;             ///< Prior P(occupied) l0 of a cell never observed. (Default: 0.5)

  /// Throws std::invalid_argument naming the first inconsistent field.
  void validate() const;
};

/// The parameters converted once into the float log-odds the cells store.
class LogOddsModel {
 public:
  explicit LogOddsModel(const LogOddsParams& p = {});

  const LogOddsParams& params() const { return params_; }
  float hitDelta() const { return hit_delta_; }    ///< l_meas(hit) - l0
  float missDelta() const { return miss_delta_; }  ///< l_meas(miss) - l0
  float prior() const { return l0_; }
  float clampMin() const { return min_; }
  float clampMax() const { return max_; }
  float occupiedThreshold() const { return occ_; }

  /// One Bayes update of a cell's log-odds, clamped to [µmin, µmax].
  float update(float prev, float delta) const {
    // min/max rather than nested conditions: compiles to minss/maxss, no branch.
    return std::min(std::max(prev + delta, min_), max_);
  }
  /// Value of a cell created by its first measurement.
  float first(float delta) const { return update(l0_, delta); }
  bool isClamped(float v) const { return v == min_ || v == max_; }
  CellState classify(float v) const { return v >= occ_ ? CellState::Occupied : CellState::Free; }

 private:
  LogOddsParams params_;
  float hit_delta_, miss_delta_, l0_, min_, max_, occ_;
};

}  // namespace rtog
