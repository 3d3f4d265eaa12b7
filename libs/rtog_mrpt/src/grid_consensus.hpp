// Private to librtog_mrpt: MRPT's lmConsensus with the bounds check MRPT's lacks.
#pragma once

#include <optional>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose2D.h>

namespace rtog {

/// COccupancyGridMap2D::computeObservationLikelihood_Consensus (MRPT 2.5.8) on `g`: the same
/// points (the scan's own auxiliary points map), the same arithmetic, so the same double wherever
/// MRPT's reads a cell of the grid. MRPT reads the cell of every end point unchecked (a SIGSEGV for
/// end points beyond the grid, or non-finite ones); here such an end point reads as an unknown
/// cell, what a grid grown to hold it holds. std::nullopt for what MRPT scores without reading a
/// cell (not exactly a CObservation2DRangeScan, or not planar by g's tolerance): the caller then
/// asks MRPT's own method.
std::optional<double> boundedConsensusLikelihood(const mrpt::maps::COccupancyGridMap2D& g,
                                                 const mrpt::obs::CObservation& obs, const mrpt::poses::CPose2D& pose);

}  // namespace rtog
