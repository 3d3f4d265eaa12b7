// Incremental discovery on the map (the estimator seed, section 4) and occupancy as a field
// (section 1). Unknown space is where no leaf is, so a frontier (a free cell face-adjacent to
// unknown space) is found from the free leaves' faces: the part of a face that no neighbouring
// leaf covers, without expanding a merged cuboid into its cells. The field O(x) interpolates the
// cells' log-odds between their centres, unknown cells at the prior.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rtog/core/key.hpp"
#include "rtog/core/occupancy_map.hpp"
#include "rtog/core/plan.hpp"

namespace rtog {

/// Frontiers in 3D: the free cells with a face neighbour that is unknown (no leaf holds it; a
/// neighbour beyond the key range is not unknown space, the map cannot hold it). In 2D, the
/// columns of a height band as its 2D view shows them (band.hpp: a column is known if the band
/// holds a known cell of it, free if its highest log-odds is free): the free columns with a
/// 4-neighbour column that is unknown.
struct FrontierOptions {
  bool planar = false;                     ///< 2D (a height band) rather than 3D. (Default: false)
  double min_z = -1000.0, max_z = 1000.0;  ///< planar: the band [m]. (Default: all)
  /// Frontier regions smaller than this many cells are dropped (sensor speckle). (Default: 1)
  std::int64_t min_region_cells = 1;
};

/// The frontier cells as disjoint boxes, each inside one leaf (3D) or one row of columns of the
/// band (planar: z of the box is the band's z-range), in a deterministic order.
std::vector<Box> frontierCells(const OccupancyMap& map, const FrontierOptions& options = {});

/// A connected set of frontier cells (26-connected in 3D, 8-connected columns in 2D).
struct FrontierRegion {
  std::vector<Box> boxes;       ///< its cells (frontierCells' boxes, whole)
  std::int64_t cells = 0;       ///< cells (planar: columns)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< mean of the cells' centres [m]
  /// The mean direction from its cells into the unknown: the sum of the unit normals of the
  /// cell faces that meet unknown space, normalized (zero if they cancel).
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

/// The frontier cells grouped into connected regions, largest first (ties: by first box). Throws
/// std::invalid_argument for min_z > max_z or min_region_cells < 1.
std::vector<FrontierRegion> frontierRegions(const OccupancyMap& map, const FrontierOptions& options = {});

/// The occupancy field at a point: log-odds interpolated between cell centres, trilinearly in 3D
/// (bilinearly between the band's columns in 2D), unknown cells at the prior l0; continuous
/// everywhere, equal to the cell's value at a cell centre.
struct FieldValue {
  double log_odds = 0.0;
  double probability = 0.5;
  /// d log_odds / d x [1/m]: the interpolant's gradient (one-sided where x lies on a cell-centre
  /// plane, where the interpolant has a kink: the side towards +infinity).
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
};

/// O(x) in 3D. A point without a key, or not finite, reads the prior with a zero gradient.
FieldValue occupancyAt(const OccupancyMap& map, const Eigen::Vector3d& x);
/// O(x, y) in the band [min_z, max_z] [m] (z of the gradient 0).
FieldValue occupancyAt2D(const OccupancyMap& map, const Eigen::Vector3d& x, double min_z, double max_z);

/// A sensor whose view is scored: its rays in the sensor's frame. Laser2D: `beams` rays spread
/// evenly over `aperture` in the x-y plane, x forward. Depth: a pinhole camera of width x height
/// pixels, every `stride`-th pixel a ray, z forward, x right, y down (the optical frame).
struct ViewSensor {
  enum class Kind { Laser2D, Depth };
  Kind kind = Kind::Laser2D;
  double max_range = 8.0;   ///< [m] (Default: 8)
  double aperture = 3.14159265358979323846;  ///< Laser2D [rad] (Default: pi)
  int beams = 181;          ///< Laser2D (Default: 181)
  int width = 640, height = 480;             ///< Depth (Default: 640 x 480)
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;  ///< Depth (Default: a Kinect's)
  int stride = 8;           ///< Depth: a ray every stride-th pixel in each direction (Default: 8)
  /// The unit rays. Throws std::invalid_argument for a range, aperture, count or intrinsics that
  /// cannot make a sensor.
  std::vector<Eigen::Vector3d> rays() const;
};

/// What a view of the sensor at a pose is expected to teach the map.
struct ViewGain {
  double bits = 0.0;              ///< the expected entropy reduction, summed over the cells
  std::int64_t cells = 0;         ///< cells a ray reaches with probability > 1/2
  std::int64_t unknown_cells = 0; ///< of them, unknown now
};

/// The expected information gain of a scan from `sensor_pose` (map frame), with the map's own
/// inverse model. Each ray walks its cells out to max_range. Unknown space does not stop a ray (as
/// frontier explorers assume), nor do free cells (below the occupied threshold: their P is the
/// map's doubt, and a clamped free cell's 0.12 would end every ray within 20 cells); an occupied
/// cell stops it with its probability, so a ray reaches a cell with the product of (1 - P) of the
/// occupied cells before it; a ray stops where that falls under 1e-3. A cell reached by several rays is updated once per scan, as insertion
/// updates it: it is observed with 1 - prod over the rays of (1 - reach). Observed, it is hit with
/// its probability P (the prior for an unknown cell) and missed otherwise; its gain is
/// H(P) - [P H(l + hit) + (1 - P) H(l + miss)] with the model's clamped update, H in bits.
ViewGain informationGain(const OccupancyMap& map, const Eigen::Isometry3d& sensor_pose, const ViewSensor& sensor);

/// Candidate views around the frontier regions, scored by gain against the risk-aware path cost.
struct ViewOptions {
  ViewSensor sensor;
  FrontierOptions frontiers;   ///< planar: 2D views at sensor_z, planned in the band; else 3D
  double sensor_z = 0.3;       ///< planar: the sensor's height [m] (Default: 0.3)
  double standoff = 1.0;       ///< candidates lie this far [m] from a region's centroid (Default: 1)
  int candidates_per_region = 8;     ///< around the centroid, facing it (Default: 8)
  std::size_t max_regions = 16;      ///< the largest regions (Default: 16)
  std::size_t planned = 12;          ///< the candidates of highest gain that get a path (Default: 12)
  /// score = gain * exp(-lambda * cost): the utility of Gonzalez-Banos and Latombe, gain
  /// discounted by the path cost f(P) = Te sum T(C) + Ta length(P). (Default: 0.2)
  double lambda = 0.2;
  PlanOptions plan;            ///< Te, Ta, unknown risk, radius of the path
};

struct View {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< the sensor's pose (map frame)
  ViewGain gain;
  std::size_t region = 0;      ///< index in frontierRegions()
  bool reachable = false;      ///< a path from the start was found
  double path_cost = 0.0, path_length = 0.0;
  double score = 0.0;          ///< 0 if not reachable
};

/// The next-best views from `from`: candidates in free cells (not nearer than the plan's radius
/// to an occupied one) around the largest frontier regions, their gains, paths for the `planned`
/// of highest gain; those ranked by score, best first. Throws std::invalid_argument for bad options.
std::vector<View> nextBestViews(const OccupancyMap& map, const Eigen::Vector3d& from, const ViewOptions& options);
/// The same around `regions`, frontierRegions(map, options.frontiers) found by the caller (who
/// also shows them): the regions are not found twice.
std::vector<View> nextBestViews(const OccupancyMap& map, const std::vector<FrontierRegion>& regions,
                                const Eigen::Vector3d& from, const ViewOptions& options);

}  // namespace rtog
