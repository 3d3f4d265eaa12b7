// rtog::CRTreeOccupancyGridMap: 3D rendering as coloured cuboids.
#include <algorithm>

#include <mrpt/img/color_maps.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CSetOfTriangles.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

namespace rtog {

namespace {
using mrpt::math::TPoint3Df;

void addCuboid(mrpt::opengl::CSetOfTriangles& tris, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
               const mrpt::img::TColor& color) {
  const TPoint3Df c[8] = {
      {float(lo.x()), float(lo.y()), float(lo.z())}, {float(hi.x()), float(lo.y()), float(lo.z())},
      {float(hi.x()), float(hi.y()), float(lo.z())}, {float(lo.x()), float(hi.y()), float(lo.z())},
      {float(lo.x()), float(lo.y()), float(hi.z())}, {float(hi.x()), float(lo.y()), float(hi.z())},
      {float(hi.x()), float(hi.y()), float(hi.z())}, {float(lo.x()), float(hi.y()), float(hi.z())}};
  // Two counter-clockwise (outward) triangles per face.
  static const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {1, 2, 6, 5}, {3, 0, 4, 7}};
  for (const auto& f : faces) {
    mrpt::opengl::TTriangle t1(c[f[0]], c[f[1]], c[f[2]]), t2(c[f[0]], c[f[2]], c[f[3]]);
    t1.setColor(color);
    t2.setColor(color);
    tris.insertTriangle(t1);
    tris.insertTriangle(t2);
  }
}
}  // namespace

void CRTreeOccupancyGridMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const {
  if (!genericMapParams.enableSaveAs3DObject) return;
  auto tris = mrpt::opengl::CSetOfTriangles::Create();
  tris->setName("rtog_cuboids");
  if (renderingOptions.showFree) tris->setColorA_u8(0xff);  // per-vertex alpha decides
  const Lattice& lat = map_.lattice();
  const LogOddsModel& lm = map_.logOddsModel();
  const Box kb = map_.keyBounds();
  const double z0 = kb.isEmpty() ? 0.0 : lat.boxMin(kb).z(), z1 = kb.isEmpty() ? 1.0 : lat.boxMax(kb).z();
  const auto shown = [&](float v) {
    const bool occ = lm.classify(v) == CellState::Occupied;
    return occ ? renderingOptions.showOccupied : renderingOptions.showFree;
  };
  // Counted first: the triangles' array grown by doubling would hold up to twice them (apps
  // save the map's scene last, when the process holds the most).
  std::size_t boxes = 0;
  map_.forEachLeaf([&](const Box&, float v) { boxes += shown(v) ? 1 : 0; });
  tris->reserve(12 * std::min<std::size_t>(boxes, renderingOptions.maxBoxes));
  std::size_t drawn = 0;
  map_.forEachLeaf([&](const Box& b, float v) {
    if (drawn >= renderingOptions.maxBoxes || !shown(v)) return;
    const bool occ = lm.classify(v) == CellState::Occupied;
    const Eigen::Vector3d lo = lat.boxMin(b), hi = lat.boxMax(b);
    mrpt::img::TColor col;
    if (renderingOptions.colorByHeight) {
      const float t = float(std::clamp((0.5 * (lo.z() + hi.z()) - z0) / std::max(z1 - z0, 1e-9), 0.0, 1.0));
      col = mrpt::img::colormap(mrpt::img::cmJET, t);
    } else {
      const auto g = static_cast<uint8_t>(255.0 * (1.0 - probability(v)));
      col = mrpt::img::TColor(g, g, g);
    }
    col.A = occ ? 255 : 40;
    addCuboid(*tris, lo, hi, col);
    ++drawn;
  });
  outObj.insert(tris);
}

}  // namespace rtog
