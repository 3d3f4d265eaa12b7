// Readings of range sensors with a wide beam (sonar, IR; rtog/core/cone.hpp): each reading one
// measurement, its cone's cells weighted, the readings applied one after the other
// (UpdateSet::Kind::Sequence).
#pragma once

#include <cstddef>

#include "integrate/update_set.hpp"
#include "rtog/core/cone.hpp"
#include "rtog/core/params.hpp"

namespace rtog {

class ConeIntegrator {
 public:
  explicit ConeIntegrator(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// Every reading's cells first, so that a bad one throws before the map changes.
  UpdateSet trace(const ConeReading* readings, std::size_t n, ConeWeighting w, const InsertParams& ip);

 private:
  IntegrationContext ctx_;
};

}  // namespace rtog
