// Absolute cell values (OccupancyMap::assignCells: priors, imported grids): boxes cut at brick
// borders, grouped by brick in the order bricks first appear (UpdateSet::Kind::Assigned).
#pragma once

#include <cstddef>

#include "integrate/update_set.hpp"
#include "rtog/core/key.hpp"

namespace rtog {

class CellAssignment {
 public:
  explicit CellAssignment(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// Throws std::invalid_argument for an empty box, a box beyond the key range, boxes that
  /// overlap, or a value that is not finite or lies outside the clamping bounds.
  UpdateSet trace(const Box* boxes, const float* values, std::size_t n);

 private:
  IntegrationContext ctx_;
};

}  // namespace rtog
