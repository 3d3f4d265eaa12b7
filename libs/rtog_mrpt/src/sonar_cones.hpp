// Sonar and IR readings (CObservationRange) as cones (rtog/core/cone.hpp, doc/sonar.md): the
// helpers CRTreeOccupancyGridMap's insertion and likelihood call, taking what they need.
//
// MRPT 2.5's COccupancyGridMap2D inserts every reading of a CObservationRange at the pose of the
// first one (sensedData[0].sensorPose) and centres each cone half an aperture clockwise of that
// sensor's axis (COccupancyGridMap2D_insert.cpp: A = phi - aperture / 2, then the triangle
// A +- aperture / 2). Here each reading is at its own sensorPose with its cone about its axis.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CObservationRange.h>
#include <mrpt/poses/CPose3D.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog::sonar {

/// CRTreeOccupancyGridMap::sonarReadings: `o`'s readings as cones in the map frame, by the
/// insertion options `io`; `invalid` counts the readings dropped.
std::vector<ConeReading> readings(const mrpt::obs::CObservationRange& o, const mrpt::poses::CPose3D& robotPose,
                                  const CRTreeOccupancyGridMap::TInsertionOptions& io, std::size_t& invalid);

/// The mrpt_grid preset's insertion of `cones`: COccupancyGridMap2D's whole steps, every cone in
/// the grid's one layer, the grid grown to hold them as it grows for a scan's end points.
/// Changes `map` and `frame` only once every cone is traced.
InsertStats insertOnGrid(OccupancyMap& map, TGridFrame2D& frame, const std::vector<ConeReading>& cones,
                         const CRTreeOccupancyGridMap::TInsertionOptions& io);

/// Whether the 2D view can score `o` from `pose` at all: a finite pose, a valid cone. Checked
/// before the view is built.
bool scorable(const mrpt::obs::CObservationRange& o, const mrpt::poses::CPose3D& pose);
/// A CObservationRange's log-likelihood on the 2D view `grid` (doc/sonar.md): per echo, a Gaussian
/// (rayTracing_stdHit, mixed by LF_zHit / LF_zRandom) about the reading expected from the pose,
/// the shortest ray across its cone; nullopt where the view cannot score it (a non-finite sensor
/// pose). For a scorable() reading, with validated options; the caller holds the view's lock.
std::optional<double> likelihood(const mrpt::obs::CObservationRange& o, const mrpt::poses::CPose3D& pose,
                                 const CRTreeOccupancyGridMap::TLikelihoodOptions& lo,
                                 const mrpt::maps::COccupancyGridMap2D& grid);

/// A CObservationRange's echoes as end points on the readings' axes, for the likelihood.
void endPoints(const mrpt::obs::CObservationRange& o, const mrpt::poses::CPose3D& robotPose, ObservationBeams& out);

}  // namespace rtog::sonar
