#include "rtog/core/log_odds.hpp"

namespace rtog {

const char* toString(CellState s) {
  switch (s) {
    case CellState::Free: return "free";
    case CellState::Occupied: return "occupied";
    default: return "unknown";
  }
}

void LogOddsParams::validate() const {
  const auto open01 = [](double p, const char* name) {
    if (!(p > 0.0 && p < 1.0))
      throw std::invalid_argument(std::string("LogOddsParams: ") + name + " must lie in (0, 1), got " +
                                  std::to_string(p));
  };
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
