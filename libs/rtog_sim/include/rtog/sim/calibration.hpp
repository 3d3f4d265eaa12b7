// Calibrating an inverse sensor model against ground truth, as a robot would in a surveyed room:
// from scans taken at exactly known poses, the share of truly occupied cells among the cells
// where beams end (prob_hit) and among the cells beams cross (prob_miss).
#pragma once

#include <cstddef>
#include <vector>

#include "rtog/core/key.hpp"
#include "rtog/sim/sensors.hpp"
#include "rtog/sim/world.hpp"

namespace rtog::sim {

struct InverseModelRates {
  double prob_hit = 0.5;   ///< P(truly occupied | a return ended in the cell)
  double prob_miss = 0.5;  ///< P(truly occupied | a beam crossed the cell)
  std::size_t end_cells = 0, crossed_cells = 0;  ///< the samples behind each share
};

/// Measures the rates over `scans` (exact poses) against `truth`. A return's end cell is a hit
/// sample; the cells a beam passes before its end cell (a return) or up to its end (a
/// no-return) are miss samples, found by stepping along the beam a quarter cell at a time and
/// counting each cell once per beam. Cells outside the truth's region are skipped. Throws
/// std::invalid_argument if there is no sample of either kind.
InverseModelRates measureInverseModel(const TruthGrid& truth, const Lattice& lat, const std::vector<Scan>& scans);

}  // namespace rtog::sim
