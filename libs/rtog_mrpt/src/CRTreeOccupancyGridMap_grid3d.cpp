// rtog::CRTreeOccupancyGridMap: the mrpt_grid preset in 3D, COccupancyGridMap3D's rule and API
// (mrpt_grid3d.hpp).
#include <optional>

#include <mrpt/maps/COccupancyGridMap3D.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/opengl/COctoMapVoxels.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "mrpt_grid.hpp"
#include "mrpt_grid3d.hpp"
#include "pose_sigma.hpp"
#include "sensor_points.hpp"

namespace rtog {

using mrpt::poses::CPose3D;

void CRTreeOccupancyGridMap::setGridFrame3D(const mrpt::math::TPoint3D& lo, const mrpt::math::TPoint3D& hi,
                                            float resolution) {
  if (!isEmpty()) throw std::logic_error("rtog::CRTreeOccupancyGridMap::setGridFrame3D: the map holds cells");
  frame3d_ = mrpt_grid3d::makeFrame(static_cast<float>(lo.x), static_cast<float>(hi.x), static_cast<float>(lo.y),
                                    static_cast<float>(hi.y), static_cast<float>(lo.z), static_cast<float>(hi.z),
                                    resolution, map_.resolution());
}

namespace {
/// Every `decimation`-th point of `pts` a ray from `sensor` (COccupancyGridMap3D::insertPointCloud).
mrpt_grid3d::RaySet raysOf(double weight, const mrpt::math::TPoint3D& sensor, const mrpt::maps::CPointsMap& pts,
                           std::size_t decimation) {
  const auto& xs = pts.getPointsBufferRef_x();
  const auto& ys = pts.getPointsBufferRef_y();
  const auto& zs = pts.getPointsBufferRef_z();
  const std::size_t dec = std::max<std::size_t>(decimation, 1);
  return mrpt_grid3d::RaySet{weight, sensor, (xs.size() + dec - 1) / dec, [&xs, &ys, &zs, dec](std::size_t i) {
                               return mrpt::math::TPoint3D(xs[i * dec], ys[i * dec], zs[i * dec]);
                             }};
}
}  // namespace

bool CRTreeOccupancyGridMap::insertGrid3D(const mrpt::obs::CObservation& obs,
                                          const std::vector<pose_sigma::SigmaPose>& poses) {
  // Each pose's rays: the grid's own points (every `decimation`-th a ray, as its
  // insertPointCloud), or for point clouds, Velodyne and rotating scans their points (decimated
  // already) by the same rule.
  std::vector<mrpt::maps::CSimplePointsMap> grid(poses.size());
  std::vector<std::vector<Eigen::Vector3f>> other(poses.size());
  std::vector<mrpt_grid3d::RaySet> sets;
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    mrpt::math::TPoint3D sensor;
    if (mrpt_grid3d::gridPoints(obs, poses[i].pose, insertionOptions.decimation_3d_range, grid[i], sensor)) {
      sets.push_back(raysOf(poses[i].weight, sensor, grid[i], insertionOptions.decimation));
      continue;
    }
    detail::SensorPoints sp;
    if (!sensorPoints(obs, poses[i].pose, true, sp)) return false;
    std::vector<Eigen::Vector3f>& p = other[i];
    p.resize(sp.size());
    std::size_t dropped = 0;
    p.resize(sp.read(0, sp.size(), p.data(), nullptr, dropped));
    if (i == 0) invalid = sp.invalid + dropped;
    sets.push_back(mrpt_grid3d::RaySet{poses[i].weight, mrpt::math::TPoint3D(sp.origin.x(), sp.origin.y(), sp.origin.z()),
                                       p.size(), [&p](std::size_t j) { return mrpt::math::TPoint3D(p[j].x(), p[j].y(), p[j].z()); }});
  }
  stepRays("insertObservation", sets);
  invalidRangesSkipped += invalid;
  return true;
}

namespace {
const TGridFrame3D& definedFrame(const TGridFrame3D& f, const char* what) {
  if (!f.defined)
    throw std::logic_error(std::string("rtog::CRTreeOccupancyGridMap::") + what +
                           ": the map has no 3D grid (a 3D section, or setGridFrame3D())");
  return f;
}
}  // namespace

float CRTreeOccupancyGridMap::getCellFreeness(unsigned cx, unsigned cy, unsigned cz) const {
  const TGridFrame3D& f = definedFrame(frame3d_, "getCellFreeness");
  if (cx >= f.size_x || cy >= f.size_y || cz >= f.size_z) return 0.5f;
  const Key o = mrpt_grid3d::keyOffset(f);
  const auto v = map_.logOdds(Key{o.x + static_cast<std::int32_t>(cx), o.y + static_cast<std::int32_t>(cy),
                                  o.z + static_cast<std::int32_t>(cz)});
  const int cell = v ? mrpt_grid::cellOfValue(*v) : 0;
  return mrpt::maps::COccupancyGridMap3D::l2p(static_cast<mrpt::maps::COccupancyGridMap3D::voxelType>(cell));
}

void CRTreeOccupancyGridMap::stepRays(const char* what, const std::vector<mrpt_grid3d::RaySet>& sets) {
  const TGridFrame3D& f = definedFrame(frame3d_, what);
  syncParams();
  std::optional<RangeNoiseRule> noise;
  if (sensorModelFromString(insertionOptions.sensorModel) == SensorModel::RangeNoise)
    noise.emplace(map_.logOddsModel(), insertionOptions.toInsertParams());
  lastInsertStats = mrpt_grid3d::insertRays(map_, f, sets, mrpt_grid3d::stepsOf(insertionOptions), noise ? &*noise : nullptr);
  totalInsertStats += lastInsertStats;
  notifyMapChanged();
}

void CRTreeOccupancyGridMap::insertRay(const mrpt::math::TPoint3D& sensor, const mrpt::math::TPoint3D& end, bool) {
  // `end` in double, as the grid takes it (the points of an observation are floats).
  stepRays("insertRay", {mrpt_grid3d::RaySet{1.0, sensor, 1, [&](std::size_t) { return end; }}});
}

void CRTreeOccupancyGridMap::insertPointCloud(const mrpt::math::TPoint3D& sensor, const mrpt::maps::CPointsMap& pts,
                                              float) {
  stepRays("insertPointCloud", {raysOf(1.0, sensor, pts, insertionOptions.decimation)});
}

void CRTreeOccupancyGridMap::getAsOctoMapVoxels(mrpt::opengl::COctoMapVoxels& gl) const {
  // As COccupancyGridMap3D::getAsOctoMapVoxels with its default rendering options (occupied and
  // free voxels, visible, no grid lines), over the cells this map knows (unknown ones are 0.5:
  // neither set); coloured as the grid colours them in the FIXED, COLOR_FROM_HEIGHT and
  // COLOR_FROM_OCCUPANCY modes, in the general colour otherwise.
  using mrpt::opengl::COctoMapVoxels;
  const TGridFrame3D& f = definedFrame(frame3d_, "getAsOctoMapVoxels");
  const Key o = mrpt_grid3d::keyOffset(f);
  gl.clear();
  gl.resizeVoxelSets(2);
  const mrpt::math::TPoint3D bbmin(f.x_min, f.y_min, f.z_min);
  const mrpt::math::TPoint3D bbmax(f.x_min + f.size_x * f.resolution, f.y_min + f.size_y * f.resolution,
                                   f.z_min + f.size_z * f.resolution);
  const mrpt::img::TColorf general = gl.getColor();
  const float inv_dz = 1.0f / static_cast<float>(bbmax.z - bbmin.z + 0.01f);
  const double L = 0.5 * f.resolution;
  map_.forEachLeaf([&](const Box& b, float v) {
    const float occ = 1.0f - mrpt::maps::COccupancyGridMap3D::l2p(
                                 static_cast<mrpt::maps::COccupancyGridMap3D::voxelType>(mrpt_grid::cellOfValue(v)));
    const bool occupied = occ > 0.501f, free = occ < 0.499f;
    if (!occupied && !free) return;
    for (std::int32_t kz = b.min.z; kz <= b.max.z; ++kz)
      for (std::int32_t ky = b.min.y; ky <= b.max.y; ++ky)
        for (std::int32_t kx = b.min.x; kx <= b.max.x; ++kx) {
          const std::int64_t cx = kx - o.x, cy = ky - o.y, cz = kz - o.z;
          if (cx < 0 || cy < 0 || cz < 0 || cx >= f.size_x || cy >= f.size_y || cz >= f.size_z) continue;
          const double x = f.x_min + cx * f.resolution + L, y = f.y_min + cy * f.resolution + L,
                       z = f.z_min + cz * f.resolution + L;
          const auto scaled = [&](float k) {
            return mrpt::img::TColor(static_cast<uint8_t>(k * general.R), static_cast<uint8_t>(k * general.G),
                                     static_cast<uint8_t>(k * general.B), static_cast<uint8_t>(255 * general.A));
          };
          mrpt::img::TColor c = general.asTColor();
          if (gl.getVisualizationMode() == COctoMapVoxels::COLOR_FROM_OCCUPANCY)
            c = scaled(240 * (1 - occ) + 15);
          else if (gl.getVisualizationMode() == COctoMapVoxels::COLOR_FROM_HEIGHT)
            c = scaled(255 * inv_dz * static_cast<float>(z - bbmin.z));
          gl.push_back_Voxel(occupied ? mrpt::opengl::VOXEL_SET_OCCUPIED : mrpt::opengl::VOXEL_SET_FREESPACE,
                             COctoMapVoxels::TVoxel(mrpt::math::TPoint3D(x, y, z), 2 * L, c));
        }
  });
  gl.setBoundingBox(bbmin, bbmax);
}

}  // namespace rtog
