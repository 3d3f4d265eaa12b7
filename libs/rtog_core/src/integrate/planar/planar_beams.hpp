// A beam-model scan in one z-layer: its beams set out in planar form, then marked into planar
// batches for the planar cache (UpdateSet::Kind::Planar).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "integrate/update_set.hpp"
#include "rtog/core/params.hpp"
#include "rtog/core/point_source.hpp"

namespace rtog {

class Lattice;

/// True if every traced beam of the scan stays in the origin's z-layer and the scan is not too
/// wide for a planar batch: then the beams in exact planar form, with the runs each can skip
/// (fanSkipRuns), are in `beams`, [lo, hi] bounds their cells in x and y, and `stats` counts them.
bool preparePlanarBeams(const Lattice& lattice, const Eigen::Vector3d& origin, const Eigen::Vector3f* points,
                        std::size_t count, const InsertParams& ip, const std::uint8_t* is_hit,
                        std::vector<PlanarBeam>& beams, Key& lo, Key& hi, InsertStats& stats);

/// The beams preparePlanarBeams() set out in the scratch, marked into its planar batches on the
/// insertion threads.
UpdateSet markPlanarBeams(const IntegrationContext& ctx, const Eigen::Vector3d& origin, std::size_t count,
                          const InsertParams& ip, const Key& lo, const Key& hi, InsertStats stats);

/// False if the source's first beams leave the origin's z-layer (then no planar batch takes it).
bool mayBePlanar(const Lattice& lattice, const Eigen::Vector3d& origin, const PointSource& source,
                 const InsertParams& ip);

}  // namespace rtog
