// Skipping the cells near the origin that other beams of a fan mark anyway.
#pragma once

#include <cstddef>

#include "integrate/planar/planar_batch.hpp"

namespace rtog {

/// For the beams of one scan from one origin (one start cell and one rounded start point), in
/// the order of a scanner's sweep: sets each beam's skip_runs so that marking every beam
/// without its skipped runs marks the same cells as the full walks.
/// Beams closer in angle than a cell's width near the origin cross the same cells there, so
/// beam i (i = odd * 2^k) leaves out the cells within the radius where, between beams i - 2^k
/// and i + 2^k, no cell fits that neither crosses; those two have larger k, so by induction
/// the cells they leave out are marked by others. Beams out of sweep order are walked whole.
void fanSkipRuns(PlanarBeam* beams, std::size_t count);

}  // namespace rtog
