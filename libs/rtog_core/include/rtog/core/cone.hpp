// Sonar and IR range sensors: one reading stands for a cone, not a ray. The echo came from
// somewhere on the arc at the reading's range, and nothing nearer inside the cone echoed
// (Elfes 1987; doc/sonar.md). The cone is taken in the horizontal plane of the sensor, the
// z-layer of cells its origin lies in, as a 2D grid (and MRPT's COccupancyGridMap2D) takes it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtog/core/key.hpp"
#include "rtog/core/log_odds.hpp"

namespace rtog {

/// How the evidence of a reading is weighted across its cone, by the angle theta of a cell's
/// centre from the axis (|theta| <= aperture / 2).
enum class ConeWeighting {
  Uniform,  ///< every cell of the cone takes the whole step, as COccupancyGridMap2D does
  Elfes,    ///< the step scaled by 1 - (2 theta / aperture)^2, full on the axis, none at the rim
};
const char* toString(ConeWeighting w);
ConeWeighting coneWeightingFromString(const std::string& s);  ///< throws std::invalid_argument

/// One reading of a range sensor with a beam of finite width.
struct ConeReading {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< sensor position, map frame [m]
  double yaw = 0.0;       ///< direction of the cone's axis in the map's x-y plane [rad]
  double aperture = 0.0;  ///< full opening angle [rad], in [0, pi]
  double range = 0.0;     ///< the reading [m], > 0
  /// True if the sensor echoed at `range`; false for a reading with no echo up to `range`
  /// (the cone is then free up to it and nothing is occupied).
  bool hit = true;
};

/// A cell of a reading's cone and the share of the step it takes.
struct ConeCell {
  std::int32_t x = 0, y = 0;
  StepKind kind = StepKind::Free;  ///< Occupied on the arc of a hit, else Free or FreeNoEcho
  float weight = 1.0f;             ///< in (0, 1]
};

/// The cells of a reading's cone in the z-layer `*layer` of its origin, each once, in
/// ascending (y, x). A cell whose centre is within the aperture of the axis (weight above 0) is
/// Free if the centre is nearer than range - half a cell, and for a hit on the arc (Occupied) if
/// it is within half a cell of the range. The cells the axis itself crosses are always in, as
/// the beam model traces a beam (free before the end cell, the end cell occupied for a hit and
/// left out for no echo, weight 1), so a cone of zero aperture is exactly the one beam. Occupied
/// wins where both claim a cell; otherwise the larger weight. Throws std::invalid_argument for a
/// range not positive and finite, an aperture outside [0, pi], a non-finite origin or yaw, and
/// std::out_of_range if the origin or the end point has no key.
void coneCells(const Lattice& lattice, const ConeReading& r, ConeWeighting w, std::vector<ConeCell>& out,
               std::int32_t* layer);

}  // namespace rtog
