// Parameters and statistics: names, validation, sums.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include "rtog/core/params.hpp"
#include "rtog/core/stats.hpp"

namespace rtog {

int defaultThreadCount() {
  static const int n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return n;
}

const char* toString(SensorModel m) {
  switch (m) {
    case SensorModel::BeamBased: return "beam";
    case SensorModel::BeamEndPoint: return "endpoint";
    default: return "rangeNoise";
  }
}

const char* toString(MergePolicy m) {
  switch (m) {
    case MergePolicy::Off: return "off";
    case MergePolicy::Clamped: return "clamped";
    default: return "equal";
  }
}

SensorModel sensorModelFromString(const std::string& s) {
  if (s == "beam" || s == "beam_based" || s == "BeamBased") return SensorModel::BeamBased;
  if (s == "endpoint" || s == "beam_end_point" || s == "BeamEndPoint") return SensorModel::BeamEndPoint;
  if (s == "rangeNoise" || s == "range_noise" || s == "RangeNoise") return SensorModel::RangeNoise;
  throw std::invalid_argument("unknown sensor model '" + s + "' (expected 'beam', 'endpoint' or 'rangeNoise')");
}

MergePolicy mergePolicyFromString(const std::string& s) {
  if (s == "off" || s == "false" || s == "0") return MergePolicy::Off;
  if (s == "clamped" || s == "true" || s == "1") return MergePolicy::Clamped;
  if (s == "equal") return MergePolicy::Equal;
  throw std::invalid_argument("unknown merge policy '" + s + "' (expected 'off', 'clamped' or 'equal')");
}

void MapParams::validate() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution) || resolution < 1e-4 || resolution > 1e3)
    throw std::invalid_argument("MapParams: resolution must lie in [1e-4, 1e3] m, got " + std::to_string(resolution));
  log_odds.validate();
  rtree.validate();
}

void InsertParams::validate() const {
  if (threads < 1) throw std::invalid_argument("InsertParams: threads must be >= 1");
  const auto nonNegative = [](double v, const char* name) {
    if (!(std::isfinite(v) && v >= 0.0))
      throw std::invalid_argument(std::string("InsertParams: ") + name + " must be finite and >= 0, got " +
                                  std::to_string(v));
  };
  nonNegative(range_noise_std, "range_noise_std");
  nonNegative(range_noise_std_per_meter, "range_noise_std_per_meter");
  if (!(std::isfinite(graded_unit) && graded_unit >= 0.0))
    throw std::invalid_argument("InsertParams: graded_unit must be finite and >= 0, got " + std::to_string(graded_unit));
  if (!(range_noise_cutoff >= 0.5 && range_noise_cutoff <= 10.0))
    throw std::invalid_argument("InsertParams: range_noise_cutoff must lie in [0.5, 10] sigma, got " +
                                std::to_string(range_noise_cutoff));
}

namespace {
// Every count of InsertStats, once: the sum and the comparison go over this list.
constexpr std::size_t InsertStats::*kCounts[] = {
    &InsertStats::rays_hit,         &InsertStats::rays_truncated,      &InsertStats::skipped_non_finite,
    &InsertStats::skipped_zero_length, &InsertStats::skipped_out_of_range, &InsertStats::skipped_too_long,
    &InsertStats::skipped_over_budget, &InsertStats::cells_occupied,   &InsertStats::cells_free,
    &InsertStats::cells_unchanged,  &InsertStats::leaves_created,      &InsertStats::leaves_merged,
    &InsertStats::leaves_split};
static_assert(sizeof(kCounts) / sizeof(kCounts[0]) * sizeof(std::size_t) == sizeof(InsertStats),
              "a count of InsertStats is missing from kCounts");
}  // namespace

InsertStats& InsertStats::operator+=(const InsertStats& o) {
  for (const auto count : kCounts) this->*count += o.*count;
  return *this;
}

bool InsertStats::operator==(const InsertStats& o) const {
  for (const auto count : kCounts)
    if (this->*count != o.*count) return false;
  return true;
}

}  // namespace rtog
