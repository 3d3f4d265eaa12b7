// Export of the occupied cuboids as a triangle mesh (PLY).
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>

#include "rtog/core/occupancy_map.hpp"

namespace rtog {

enum class PlyEncoding {
  Ascii,               ///< `format ascii 1.0`
  BinaryLittleEndian,  ///< `format binary_little_endian 1.0` (compact; the default)
};

struct MeshExportStats {
  std::size_t cuboids = 0;   ///< occupied leaves written
  std::size_t vertices = 0;  ///< 8 per cuboid
  std::size_t faces = 0;     ///< 12 triangles per cuboid
};

/// An RGB colour for a height fraction t in [0, 1] (blue, cyan, green, yellow, red; clamped).
struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};
Rgb heightColor(double t);

/// Writes every occupied leaf of `map` as a closed box: 8 vertices (metres, float) and 12
/// triangles with outward (counter-clockwise) winding. Vertex properties `x y z red green blue`,
/// the colour by the vertex's height over the occupied cuboids' z range; faces are
/// `list uchar int vertex_indices`. Free and unknown space is not written.
/// Throws std::length_error if the vertex indices would overflow a PLY `int` and
/// std::runtime_error if the stream fails.
MeshExportStats writeOccupiedPly(const OccupancyMap& map, std::ostream& os,
                                 PlyEncoding encoding = PlyEncoding::BinaryLittleEndian);

}  // namespace rtog
