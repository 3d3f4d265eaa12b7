// Plain types of the MRPT map types: an observation's beams in the map frame, and the geometry
// of the COccupancyGridMap2D the mrpt_grid preset follows.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rtog {

/// Beams of one observation in the map frame, ready for the core map.
struct ObservationBeams {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< sensor position (map frame)
  std::vector<Eigen::Vector3f> points;               ///< beam end points (map frame)
  std::vector<std::uint8_t> is_hit;                  ///< 1: return, 0: no-return beam
  std::vector<float> ranges;                         ///< measured range of each beam [m], if `with_ranges`
  bool with_ranges = true;  ///< false: `ranges` stays empty (insertion reads none; a depth frame's are 1 MB)
  std::size_t invalid = 0;                           ///< beams dropped as invalid (no range)
  /// Empties, keeping the buffers' capacity for the next observation.
  void clear() {
    origin.setZero();
    points.clear();
    is_hit.clear();
    ranges.clear();
    invalid = 0;
  }
};

/// The geometry a COccupancyGridMap2D would have grown to from the same observations (the
/// mrpt_grid preset keeps it: the grid's float extent decides the cell a point falls in).
struct TGridFrame2D {
  float x_min{-10.0f}, x_max{10.0f}, y_min{-10.0f}, y_max{10.0f};
  float resolution{0.10f};
  std::uint32_t size_x{0}, size_y{0};
  /// The grid is one plane: every 2D scan steps the cells of one z-layer of the lattice, the
  /// layer of the first one's sensor height.
  bool has_layer{false};
  std::int32_t layer{0};
  bool sameGeometry(const TGridFrame2D& o) const {
    return x_min == o.x_min && x_max == o.x_max && y_min == o.y_min && y_max == o.y_max &&
           resolution == o.resolution && size_x == o.size_x && size_y == o.size_y;
  }
};

/// The geometry of the COccupancyGridMap3D that a 3D section describes (its _creationOpts has
/// min_z or max_z): the extent and cell edge as CDynamicGrid3D::setSize() makes them, in double
/// from the section's floats. 3D observations in the mrpt_grid preset step the cells of this grid
/// (mrpt_grid3d). Without a 3D section (`defined` false) 3D observations follow the clamp-and-add
/// rule (doc/mrpt_map.md): COccupancyGridMap2D, whose section it is, takes none.
struct TGridFrame3D {
  bool defined{false};
  double x_min{0}, y_min{0}, z_min{0};
  double resolution{0};
  std::uint32_t size_x{0}, size_y{0}, size_z{0};
  bool operator==(const TGridFrame3D& o) const {
    return defined == o.defined && x_min == o.x_min && y_min == o.y_min && z_min == o.z_min &&
           resolution == o.resolution && size_x == o.size_x && size_y == o.size_y && size_z == o.size_z;
  }
};

}  // namespace rtog
