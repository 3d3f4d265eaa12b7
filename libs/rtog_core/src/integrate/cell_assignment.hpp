// Absolute cell values (OccupancyMap::assignCells: priors, imported grids; read()): boxes cut at
// brick borders into pieces, grouped by brick in the order bricks first appear, checked disjoint
// (UpdateSet::Kind::Assigned).
#pragma once

#include <cstddef>

#include "integrate/update_set.hpp"
#include "rtog/core/key.hpp"

namespace rtog {

class CellAssignment {
 public:
  explicit CellAssignment(const IntegrationContext& ctx) : ctx_(ctx) {}
  /// Throws std::invalid_argument for an empty box, a box beyond the key range, boxes that
  /// overlap, boxes spanning more than 2^26 bricks, or a value that is not finite or lies outside
  /// the clamping bounds.
  UpdateSet trace(const Box* boxes, const float* values, std::size_t n);
  /// The pieces already in the scratch (`assigned`: each inside its brick, values checked), as a
  /// map file holds them: grouped here unless each brick's pieces are together already; throws
  /// std::invalid_argument for pieces that overlap.
  UpdateSet tracePieces();

 private:
  IntegrationContext ctx_;
};

}  // namespace rtog
