#include "rtog/core/log_odds.hpp"

namespace rtog {
namespace {
void requireOpenUnit(const char* type, const char* name, double v) {
  if (!(v > 0.0 && v < 1.0))
    throw std::invalid_argument(std::string(type) + ": " + name + " must lie in (0, 1), got " + std::to_string(v));
}
}  // namespace

const char* toString(CellState s) {
  switch (s) {
    case CellState::Free: return "free";
    case CellState::Occupied: return "occupied";
    default: return "unknown";
  }
}

void LogOddsParams::validate() const {
  const auto open01 = [](double p, const char* name) { requireOpenUnit("LogOddsParams", name, p); };
  open01(prob_hit, "prob_hit");
  open01(prob_miss, "prob_miss");
  open01(clamp_min, "clamp_min");
  open01(clamp_max, "clamp_max");
  open01(occupied_threshold, "occupied_threshold");
  open01(prior, "prior");
  if (!(prob_hit > prior)) throw std::invalid_argument("LogOddsParams: prob_hit must exceed prior");
  if (!(prob_miss < prior)) throw std::invalid_argument("LogOddsParams: prob_miss must be below prior");
  if (!(clamp_min < prior && prior < clamp_max))
    throw std::invalid_argument("LogOddsParams: need clamp_min < prior < clamp_max");
}

void SensorChannel::validate() const {
  const auto open01 = [](double r, const char* name) { requireOpenUnit("SensorChannel", name, r); };
  open01(miss_rate, "miss_rate");
  open01(false_alarm_rate, "false_alarm_rate");
  if (!(miss_rate + false_alarm_rate < 1.0))
    throw std::invalid_argument("SensorChannel: miss_rate + false_alarm_rate must be below 1, got " +
                                std::to_string(miss_rate + false_alarm_rate));
}

LogOddsParams withChannel(LogOddsParams p, const SensorChannel& c) {
  c.validate();
  const double l0 = logit(p.prior);
  p.prob_hit = probability(l0 + std::log((1.0 - c.miss_rate) / c.false_alarm_rate));
  p.prob_miss = probability(l0 + std::log(c.miss_rate / (1.0 - c.false_alarm_rate)));
  return p;
}

SensorChannel channelOf(const LogOddsParams& p) {
  p.validate();
  // a = (1 - m) / f and b = m / (1 - f), the odds ratios of a detection and of none.
  const double l0 = logit(p.prior);
  const double a = std::exp(logit(p.prob_hit) - l0), b = std::exp(logit(p.prob_miss) - l0);
  SensorChannel c;
  c.false_alarm_rate = (1.0 - b) / (a - b);
  c.miss_rate = b * (a - 1.0) / (a - b);
  return c;
}

LogOddsModel::LogOddsModel(const LogOddsParams& p) : params_(p) {
  p.validate();
  l0_ = static_cast<float>(logit(p.prior));
  hit_delta_ = static_cast<float>(logit(p.prob_hit) - logit(p.prior));
  miss_delta_ = static_cast<float>(logit(p.prob_miss) - logit(p.prior));
  min_ = static_cast<float>(logit(p.clamp_min));
  max_ = static_cast<float>(logit(p.clamp_max));
  occ_ = static_cast<float>(logit(p.occupied_threshold));
}

}  // namespace rtog
