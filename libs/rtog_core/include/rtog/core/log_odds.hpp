// Log-odds occupancy: the Bayes update l = l_prev + l_meas - l0 with clamping.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

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

/// The sensor stated as a binary asymmetric channel (seed §2; Robbiano et al., 2019): for each
/// cell a beam reports a detection (it ended there) or none (it passed through). A sensor that
/// misses an occupied cell with probability m = miss_rate and reports a free cell as occupied
/// with probability f = false_alarm_rate changes a cell's log-odds, by Bayes' rule, by
///   log((1 - m) / f)      for a detection,   and   log(m / (1 - f))   for none,
/// which are the l_meas - l0 of the inverse model with prob_hit = sigmoid(l0 + log((1 - m) / f))
/// and prob_miss = sigmoid(l0 + log(m / (1 - f))). The defaults are the channel of the default
/// LogOddsParams (OctoMap's 0.7 / 0.4 at prior 0.5).
struct SensorChannel {
  double miss_rate = 8.0 / 15.0;   ///< P(no detection | occupied). (Default: 8/15)
  double false_alarm_rate = 0.2;   ///< P(detection | free). (Default: 0.2)

  /// Throws std::invalid_argument unless both rates lie in (0, 1) and miss_rate +
  /// false_alarm_rate < 1 (else a detection would not speak for occupied).
  void validate() const;
};

/// `p` with prob_hit and prob_miss those of the channel, for p's prior.
LogOddsParams withChannel(LogOddsParams p, const SensorChannel& channel);
/// The channel whose hit and miss probabilities are p's (p must be valid).
SensorChannel channelOf(const LogOddsParams& p);

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

/// What one beam did to one cell, for a grid that updates beam by beam (StepRule).
enum class StepKind : std::uint8_t {
  Free = 0,        ///< crossed by a beam that returned
  FreeNoEcho = 1,  ///< crossed by a no-return beam
  Occupied = 2,    ///< the end cell of a beam that returned
};

/// The update of a grid whose cells take one step per beam, in beam order, with integer
/// log-odds that saturate (MRPT's COccupancyGridMap2D/3D): a step moves a cell by its kind's
/// delta unless the cell is within a step of its kind's bound, which it then takes. Saturating
/// steps do not commute, so the order of the steps is part of the result; OctoMap's rule
/// (LogOddsModel::update, one update per cell and scan) is the other rule the map holds.
struct StepRule {
  float delta[3] = {0, 0, 0};  ///< signed change per kind (index: StepKind)
  float limit[3] = {0, 0, 0};  ///< free kinds step while v > limit, occupied while v < limit
  float bound[3] = {0, 0, 0};  ///< the value taken otherwise

  float apply(float v, StepKind kind) const {
    const auto i = static_cast<std::size_t>(kind);
    const bool steps = kind == StepKind::Occupied ? v < limit[i] : v > limit[i];
    return steps ? v + delta[i] : bound[i];
  }
};

/// Cells a beam steps in one z-layer, as grids raster beams in fixed point: cell k (k < count)
/// is (((x << F) + k * dx) >> F, ((y << F) + k * dy) >> F) for F = kStepRunFracBits, each taking
/// a `kind` step; then, if `end`, the cell (end_x, end_y) takes an Occupied step.
struct StepRun {
  std::int32_t x, y, dx, dy;
  std::uint32_t count;
  StepKind kind;
  bool end;
  std::int32_t end_x, end_y;
  /// The run's cells are those of steps [skip, skip + count) of the raster from cell (x, y) (its
  /// corner, in 2^-kStepRunFracBits cells) by (dx, dy): a run cut at a region's border keeps the
  /// raster it was cut from. (Default: 0)
  std::uint32_t skip = 0;
};
constexpr int kStepRunFracBits = 9;

/// Calls fn(x, y, kind) for every cell of a run, in its order.
template <class Fn>
void forEachRunCell(const StepRun& r, Fn&& fn) {
  std::int32_t fx = r.x * (1 << kStepRunFracBits) + static_cast<std::int32_t>(r.skip) * r.dx;
  std::int32_t fy = r.y * (1 << kStepRunFracBits) + static_cast<std::int32_t>(r.skip) * r.dy;
  for (std::uint32_t k = 0; k < r.count; ++k, fx += r.dx, fy += r.dy)
    fn(fx >> kStepRunFracBits, fy >> kStepRunFracBits, r.kind);
  if (r.end) fn(r.end_x, r.end_y, StepKind::Occupied);
}

}  // namespace rtog
