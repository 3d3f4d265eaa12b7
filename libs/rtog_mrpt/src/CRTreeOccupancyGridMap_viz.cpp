// rtog::CRTreeOccupancyGridMap: 3D rendering as coloured cuboids (cuboid_scene.hpp).
#include <algorithm>
#include <limits>
#include <stdexcept>

#include <mrpt/img/color_maps.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/serialization/CArchive.h>

#include "cuboid_scene.hpp"

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

bool shown(const CRTreeOccupancyGridMap& m, float v) {
  const bool occ = m.map().logOddsModel().classify(v) == CellState::Occupied;
  return occ ? m.renderingOptions.showOccupied : m.renderingOptions.showFree;
}

std::vector<std::uint8_t> bytesOf(const mrpt::serialization::CSerializable& o) {
  mrpt::io::CMemoryStream mem;
  mrpt::serialization::archiveFrom(mem) << o;
  const auto* p = static_cast<const std::uint8_t*>(mem.getRawBufferData());
  return {p, p + mem.getTotalBytesCount()};
}

}  // namespace

mrpt::opengl::CSetOfTriangles::Ptr cuboidSet(const CRTreeOccupancyGridMap& m) {
  auto tris = mrpt::opengl::CSetOfTriangles::Create();
  tris->setName("rtog_cuboids");
  if (m.renderingOptions.showFree) tris->setColorA_u8(0xff);  // per-vertex alpha decides
  return tris;
}

std::size_t cuboidsDrawn(const CRTreeOccupancyGridMap& m) {
  std::size_t boxes = 0;
  m.map().forEachLeaf([&](const Box&, float v) { boxes += shown(m, v) ? 1 : 0; });
  return std::min<std::size_t>(boxes, m.renderingOptions.maxBoxes);
}

void drawCuboids(const CRTreeOccupancyGridMap& m, std::size_t total, mrpt::opengl::CSetOfTriangles& tris,
                 std::size_t chunk, const std::function<void()>& emit) {
  chunk = std::max<std::size_t>(chunk, 1);
  // Reserved exactly: a set grown by doubling would hold up to twice its triangles.
  tris.reserve(12 * std::min(total, chunk));
  const Lattice& lat = m.map().lattice();
  const LogOddsModel& lm = m.map().logOddsModel();
  const Box kb = m.map().keyBounds();
  const double z0 = kb.isEmpty() ? 0.0 : lat.boxMin(kb).z(), z1 = kb.isEmpty() ? 1.0 : lat.boxMax(kb).z();
  std::size_t drawn = 0, in_set = 0;
  m.map().forEachLeaf([&](const Box& b, float v) {
    if (drawn >= total || !shown(m, v)) return;
    const bool occ = lm.classify(v) == CellState::Occupied;
    const Eigen::Vector3d lo = lat.boxMin(b), hi = lat.boxMax(b);
    mrpt::img::TColor col;
    if (m.renderingOptions.colorByHeight) {
      const float t = float(std::clamp((0.5 * (lo.z() + hi.z()) - z0) / std::max(z1 - z0, 1e-9), 0.0, 1.0));
      col = mrpt::img::colormap(mrpt::img::cmJET, t);
    } else {
      const auto g = static_cast<uint8_t>(255.0 * (1.0 - probability(v)));
      col = mrpt::img::TColor(g, g, g);
    }
    col.A = occ ? 255 : 40;
    addCuboid(tris, lo, hi, col);
    ++drawn;
    if (++in_set == chunk && drawn < total) {
      emit();
      tris.clearTriangles();
      in_set = 0;
    }
  });
  emit();
}

void CRTreeOccupancyGridMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& outObj) const {
  if (!genericMapParams.enableSaveAs3DObject) return;
  auto all = cuboidSet(*this);
  drawCuboids(*this, cuboidsDrawn(*this), *all, std::numeric_limits<std::size_t>::max(), [] {});
  outObj.insert(all);
}

void saveCuboidScene(const CRTreeOccupancyGridMap& m, const std::string& path, std::size_t chunk) {
  chunk = std::max<std::size_t>(chunk, 1);
  mrpt::opengl::COpenGLScene scene;
  auto obj = mrpt::opengl::CSetOfObjects::Create();
  scene.insert(obj);
  if (!m.genericMapParams.enableSaveAs3DObject) {
    if (!scene.saveToFile(path)) throw std::runtime_error("cannot write '" + path + "'");
    return;
  }
  // The scene with as many empty sets as the cuboids fill, then each empty set's bytes replaced
  // by a full one's as it is drawn: an object's bytes in an MRPT archive do not depend on where
  // it is written (class name, version, data, end flag; no references between objects).
  const std::size_t total = cuboidsDrawn(m);
  const std::size_t sets = std::max<std::size_t>(1, (total + chunk - 1) / chunk);
  const auto empty = cuboidSet(m);
  for (std::size_t i = 0; i < sets; ++i) obj->insert(empty);
  const std::vector<std::uint8_t> whole = bytesOf(scene), one = bytesOf(*empty);
  std::vector<std::uint8_t> run;
  run.reserve(one.size() * sets);
  for (std::size_t i = 0; i < sets; ++i) run.insert(run.end(), one.begin(), one.end());
  const auto at = std::search(whole.begin(), whole.end(), run.begin(), run.end());
  if (at == whole.end()) throw std::logic_error("saveCuboidScene: the scene's bytes do not hold its sets");
  mrpt::io::CFileGZOutputStream f;
  if (!f.open(path)) throw std::runtime_error("cannot write '" + path + "'");
  const auto before = static_cast<std::size_t>(at - whole.begin());
  f.Write(whole.data(), before);
  auto archive = mrpt::serialization::archiveFrom(f);
  std::size_t written = 0;
  const auto tris = cuboidSet(m);
  drawCuboids(m, total, *tris, chunk, [&] {
    archive << *tris;
    ++written;
  });
  if (written != sets) throw std::logic_error("saveCuboidScene: the map drew another number of sets");
  f.Write(whole.data() + before + run.size(), whole.size() - before - run.size());
}

}  // namespace rtog
