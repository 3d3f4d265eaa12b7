// Private to librtog_mrpt: the map's cuboids as MRPT triangles, for getVisualizationInto and
// for the .3Dscene of saveMetricMapRepresentationToFile. The file is written chunk by chunk:
// apps save their map when they hold the most (rbpf-slam at the end of its run, every particle
// alive), and 12 triangles of 108 bytes a cuboid held all at once would be the run's peak.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include <mrpt/opengl/CSetOfTriangles.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

/// How many cuboids the map draws (renderingOptions: what is shown, at most maxBoxes).
std::size_t cuboidsDrawn(const CRTreeOccupancyGridMap& m);

/// An empty set of triangles as the map's cuboids are drawn into (named "rtog_cuboids").
mrpt::opengl::CSetOfTriangles::Ptr cuboidSet(const CRTreeOccupancyGridMap& m);

/// Draws the map's first `total` (cuboidsDrawn) cuboids into `tris` (from cuboidSet), `chunk` at
/// most at a time: emit() is called when it is full, then it is emptied, and once after the last
/// cuboid. That makes ceil(total / chunk) sets, at least one (empty, for a map that draws none).
void drawCuboids(const CRTreeOccupancyGridMap& m, std::size_t total, mrpt::opengl::CSetOfTriangles& tris,
                 std::size_t chunk, const std::function<void()>& emit);

/// Writes the scene getVisualizationInto draws to `path` (gzip, as COpenGLScene::saveToFile),
/// its cuboids in sets of `chunk`, holding one set at a time: the file MRPT writes for a scene
/// holding those sets. Throws std::runtime_error if it cannot be written.
void saveCuboidScene(const CRTreeOccupancyGridMap& m, const std::string& path, std::size_t chunk = 512);

}  // namespace rtog
