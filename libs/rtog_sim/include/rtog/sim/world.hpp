// A seeded synthetic world of axis-aligned boxes (rooms with walls and doors, floor, ceiling,
// pillars, furniture) with a trajectory through it, exact ray casting and exact ground truth.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"

namespace rtog::sim {

enum class BoxKind : std::uint8_t { Floor, Ceiling, Wall, Pillar, Cabinet, TableTop, TableLeg, Crate };
const char* toString(BoxKind k);

/// A closed axis-aligned box [min, max] in metres.
struct SolidBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  BoxKind kind = BoxKind::Wall;
};

/// Slab test of the ray o + t d (t >= 0) against a closed box: the smallest t >= 0 inside the
/// box (0 when o is inside), or nothing. `d` need not be normalized; t is in units of |d|.
std::optional<double> intersectRayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const SolidBox& b);

/// A robot pose on the floor: position (z = floor top) and heading.
struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0.0;
};

struct WorldParams {
  int rooms_x = 3, rooms_y = 2;                   ///< grid of rooms
  double room_min = 4.5, room_max = 6.5;          ///< room size range along x and y [m]
  double height_min = 2.6, height_max = 3.0;      ///< floor-to-ceiling height range [m]
  double wall_thickness = 0.2;
  double slab_thickness = 0.2;                    ///< floor and ceiling slabs
  double door_width = 1.0, door_height = 2.1;
  double extra_door_probability = 0.5;            ///< doors between rows besides the path's
  int pillars_max = 2;                            ///< per room, 0..max
  int furniture_min = 2, furniture_max = 5;       ///< per room
  double clearance = 0.6;                         ///< furniture keeps this far from the path [m]
  double pose_spacing = 0.5;                      ///< largest distance between consecutive poses [m]
  void validate() const;                          ///< throws std::invalid_argument
};

/// The first surface a ray meets.
struct RayHit {
  double t = 0.0;        ///< distance along the (unit) direction [m]
  std::size_t box = 0;   ///< index into World::boxes()
};

class World {
 public:
  /// Builds a world and its trajectory from a seed (deterministic for a given seed).
  static World generate(const WorldParams& p, std::uint32_t seed);
  /// A world from explicit boxes and poses (tests).
  World(std::vector<SolidBox> boxes, std::vector<Pose> trajectory);

  const std::vector<SolidBox>& boxes() const { return boxes_; }
  const std::vector<Pose>& trajectory() const { return trajectory_; }
  const Eigen::Vector3d& boundsMin() const { return bmin_; }
  const Eigen::Vector3d& boundsMax() const { return bmax_; }
  /// Height of the floor top (poses stand on it).
  double floorZ() const { return floor_z_; }

  /// First hit of the ray origin + t * dir, 0 <= t <= max_range (dir must be unit length).
  /// Exact (slab tests), accelerated by a uniform grid of box lists.
  std::optional<RayHit> castRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                double max_range) const;

  /// True when the open box (lo, hi) overlaps the interior of some solid box, i.e. the
  /// intersection has positive volume.
  bool overlapsSolid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  /// Ground truth of a lattice cell: its volume intersects a box.
  bool cellOccupied(const Lattice& lat, const Key& k) const;
  /// True when a box contains a point (closed boxes).
  bool containsPoint(const Eigen::Vector3d& p) const;

  std::string summary() const;

 private:
  void buildGrid();
  std::vector<SolidBox> boxes_;
  std::vector<Pose> trajectory_;
  Eigen::Vector3d bmin_, bmax_;
  double floor_z_ = 0.0;
  // Uniform acceleration grid.
  double cell_ = 0.5;
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::vector<std::uint32_t> cell_start_;  // CSR offsets, size cells + 1
  std::vector<std::uint32_t> cell_boxes_;
};

/// Dense ground-truth occupancy over a key box: cell k is occupied iff its volume intersects
/// a box (for a 2D slice: iff the square cell at height z intersects a box that spans z).
class TruthGrid {
 public:
  /// All cells of `region` (inclusive keys) in 3D.
  static TruthGrid rasterize(const World& w, const Lattice& lat, const Box& region);
  /// The layer region.min.z == region.max.z of `region`, truth taken in the plane z = plane_z.
  static TruthGrid rasterizeSlice(const World& w, const Lattice& lat, const Box& region, double plane_z);

  const Box& region() const { return region_; }
  std::size_t size() const { return occ_.size(); }
  std::size_t index(const Key& k) const {
    return static_cast<std::size_t>(k.x - region_.min.x) +
           static_cast<std::size_t>(region_.extent(0)) *
               (static_cast<std::size_t>(k.y - region_.min.y) +
                static_cast<std::size_t>(region_.extent(1)) * static_cast<std::size_t>(k.z - region_.min.z));
  }
  Key key(std::size_t i) const {
    const auto ex = static_cast<std::size_t>(region_.extent(0)), ey = static_cast<std::size_t>(region_.extent(1));
    return Key{region_.min.x + static_cast<std::int32_t>(i % ex), region_.min.y + static_cast<std::int32_t>((i / ex) % ey),
               region_.min.z + static_cast<std::int32_t>(i / (ex * ey))};
  }
  /// Cells outside the region are free (no box reaches there).
  bool occupied(const Key& k) const { return region_.contains(k) && occ_[index(k)] != 0; }
  bool occupiedAt(std::size_t i) const { return occ_[i] != 0; }
  std::size_t occupiedCount() const;

 private:
  Box region_ = Box::empty();
  std::vector<std::uint8_t> occ_;
};

/// Key box of the world's bounds grown by `margin` cells.
Box worldKeyBox(const World& w, const Lattice& lat, int margin);

}  // namespace rtog::sim
