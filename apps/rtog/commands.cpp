#include "commands.hpp"
#include "rtog/app/output_files.hpp"

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/serialization/CArchive.h>

#include "gzip.hpp"
#include "rtog/mrpt/CRTreeOccupancyGridMap.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <vector>


#include "rtog/core/mesh_export.hpp"
#include "rtog/core/octomap_export.hpp"
#include "rtog/image/picture.hpp"
#include "rtog/image/slice.hpp"
#include "rtog/image/tum_dataset.hpp"

namespace rtog::cli {

void saveMap(const OccupancyMap& map, const std::string& path) {
  app::OutputSet files;
  map.write(files.add("map", path));
  files.commit();
}

namespace {
/// Mean binary entropy of the known cells' occupancy [bits]: how certain the map is (a blurred
/// insertion raises it).
double meanEntropyBits(const OccupancyMap& map) {
  double sum = 0.0;
  std::int64_t cells = 0;
  map.forEachLeaf([&](const Box& b, float l) {
    const double p = 1.0 / (1.0 + std::exp(-double(l)));
    const double h = p <= 0.0 || p >= 1.0 ? 0.0 : -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
    sum += h * double(b.volume());
    cells += b.volume();
  });
  return cells > 0 ? sum / double(cells) : 0.0;
}
}  // namespace

void printStatistics(const OccupancyMap& map, std::ostream& out) {
  const MapStatistics s = map.statistics();
  const ClassCover cover = map.classCover();
  const double res = map.resolution();
  out << "resolution        " << res << " m\n"
      << "merge policy      " << toString(map.params().merge) << "\n"
      << "leaves (cuboids)  " << s.leaves << "  (occupied " << s.occupied_leaves << ", free " << s.free_leaves
      << ")\n"
      << "cells covered     " << s.cells << "  (occupied " << s.occupied_cells << ", free " << s.free_cells << ")\n"
      << "leaves by class   " << cover.leaves() << "  (occupied " << cover.occupied << ", free " << cover.free
      << "), if only each cell's class were kept\n"
      << "cells per leaf    " << std::fixed << std::setprecision(2) << (s.leaves ? double(s.cells) / s.leaves : 0.0)
      << "\n"
      << "R-tree            height " << s.tree_height << ", " << s.tree_nodes << " nodes, " << s.bricks
      << " bricks\n"
      << "memory            " << std::setprecision(2) << s.memory_bytes / 1048576.0 << " MiB\n"
      << "entropy           " << std::setprecision(4) << meanEntropyBits(map) << " bits per known cell (mean)\n";
  const LogOddsParams& lp = map.params().log_odds;
  out.unsetf(std::ios::floatfield);
  out << std::setprecision(4) << "sensor model      hit " << lp.prob_hit << ", miss " << lp.prob_miss << ", clamp ["
      << lp.clamp_min << ", " << lp.clamp_max << "], occupied >= " << lp.occupied_threshold << ", prior "
      << lp.prior << "\n";
  if (!s.bounds.isEmpty()) {
    const auto lo = map.lattice().boxMin(s.bounds), hi = map.lattice().boxMax(s.bounds);
    out << std::setprecision(2) << "bounds            [" << lo.x() << ", " << lo.y() << ", " << lo.z() << "] .. ["
        << hi.x() << ", " << hi.y() << ", " << hi.z() << "] m\n";
  }
  out.unsetf(std::ios::floatfield);
}

int info(const std::string& map_path, bool json, std::ostream& out) {
  const OccupancyMap map = loadMap(map_path);
  if (!json) {
    printStatistics(map, out);
    return 0;
  }
  const MapStatistics s = map.statistics();
  const ClassCover cover = map.classCover();
  const LogOddsParams& lp = map.params().log_odds;
  nlohmann::json j = {{"resolution", map.resolution()},
                      {"merge", toString(map.params().merge)},
                      {"leaves", s.leaves},
                      {"occupied_leaves", s.occupied_leaves},
                      {"free_leaves", s.free_leaves},
                      {"cells", s.cells},
                      {"occupied_cells", s.occupied_cells},
                      {"free_cells", s.free_cells},
                      {"class_cover_leaves", {{"occupied", cover.occupied}, {"free", cover.free}}},
                      {"memory_bytes", s.memory_bytes},
                      {"bricks", s.bricks},
                      {"tree_height", s.tree_height},
                      {"tree_nodes", s.tree_nodes},
                      {"mean_entropy_bits", meanEntropyBits(map)},
                      {"log_odds",
                       {{"prob_hit", lp.prob_hit},
                        {"prob_miss", lp.prob_miss},
                        {"clamp_min", lp.clamp_min},
                        {"clamp_max", lp.clamp_max},
                        {"occupied_threshold", lp.occupied_threshold},
                        {"prior", lp.prior}}}};
  if (!s.bounds.isEmpty()) {
    const auto lo = map.lattice().boxMin(s.bounds), hi = map.lattice().boxMax(s.bounds);
    j["bounds_min"] = {lo.x(), lo.y(), lo.z()};
    j["bounds_max"] = {hi.x(), hi.y(), hi.z()};
  }
  out << j.dump(2) << "\n";
  return 0;
}

namespace {

std::string metres(double v) {
  std::ostringstream os;
  os << std::setprecision(6) << v;
  return os.str();
}

}  // namespace

int exportMap(const ExportOptions& opts, std::ostream& out) {
  if (opts.ply_path.empty() && opts.bt_path.empty() && opts.png_path.empty() && opts.scene_path.empty())
    throw std::invalid_argument(
        "export: nothing to do; give --ply FILE, --bt FILE, --scene FILE or --png FILE --slice-z Z");
  if (!opts.png_path.empty() && !opts.slice_z)
    throw std::invalid_argument("export: --png needs --slice-z Z (height of the slice in metres)");
  if (opts.png_path.empty() && opts.slice_z)
    throw std::invalid_argument("export: --slice-z is only used with --png FILE");
  if (opts.slice_z && !std::isfinite(*opts.slice_z))
    throw std::invalid_argument("export: --slice-z must be a finite height in metres");
  // Every output checked and opened before the map is read; written to temporaries, and
  // renamed into place only when all of them succeeded.
  app::OutputSet files({{"map", opts.map_path}});
  std::ostream* png_out = opts.png_path.empty() ? nullptr : &files.add("--png", opts.png_path);
  std::ostream* scene_out = opts.scene_path.empty() ? nullptr : &files.add("--scene", opts.scene_path);
  std::ostream* ply_out = opts.ply_path.empty() ? nullptr : &files.add("--ply", opts.ply_path);
  std::ostream* bt_out = opts.bt_path.empty() ? nullptr : &files.add("--bt", opts.bt_path);
  const OccupancyMap map = loadMap(opts.map_path);
  std::vector<std::string> messages;

  if (!opts.png_path.empty()) {
    const double z = *opts.slice_z;
    const Box bounds = map.keyBounds();
    if (bounds.isEmpty()) throw std::invalid_argument("export: the map is empty, there is no slice to draw");
    const double zlo = map.lattice().boxMin(bounds).z(), zhi = map.lattice().boxMax(bounds).z();
    if (!(z >= zlo && z < zhi))
      throw std::invalid_argument("export: --slice-z " + metres(z) + " m is outside the map's height range [" +
                                  metres(zlo) + ", " + metres(zhi) + ") m");
    const cv::Mat img = !opts.png_cells          ? image::slicePicture(map, z, opts.png_probability)
                        : opts.png_probability ? image::rasterizeSliceProbabilityZ(map, z)
                                               : image::rasterizeSliceZ(map, z);
    *png_out << image::encodePng(img);
    messages.push_back("wrote " + opts.png_path + ": slice at z = " + metres(z) + " m, " + std::to_string(img.cols) +
                       " x " + std::to_string(img.rows) + " pixels (" +
                       (opts.png_cells ? "one per cell; " : "a picture: cells scaled up, axes, scale bar, legend; ") +
                       (opts.png_probability ? "grey 255 * (1 - P(occupied)), unknown light blue)"
                                             : "occupied black, free white, unknown grey)"));
  }
  if (!opts.scene_path.empty()) {
    // The MRPT map type draws itself; the scene is a gzip-compressed CArchive, as
    // SceneViewer3D reads it.
    CRTreeOccupancyGridMap wrapper(map.resolution());
    wrapper.map() = map;
    wrapper.notifyMapChanged();
    auto cuboids = mrpt::opengl::CSetOfObjects::Create();
    wrapper.getVisualizationInto(*cuboids);
    mrpt::opengl::COpenGLScene scene;
    scene.insert(cuboids);
    mrpt::io::CMemoryStream mem;
    auto archive = mrpt::serialization::archiveFrom(mem);
    archive << scene;
    writeGzip(mem.getRawBufferData(), mem.getTotalBytesCount(), *scene_out);
    messages.push_back("wrote " + opts.scene_path + ": " + std::to_string(map.statistics().occupied_leaves) +
                       " occupied cuboids (open with SceneViewer3D)");
  }
  if (!opts.ply_path.empty()) {
    const MeshExportStats st =
        writeOccupiedPly(map, *ply_out, opts.ply_ascii ? PlyEncoding::Ascii : PlyEncoding::BinaryLittleEndian);
    messages.push_back("wrote " + opts.ply_path + ": " + std::to_string(st.cuboids) + " occupied cuboids, " +
                       std::to_string(st.vertices) + " vertices, " + std::to_string(st.faces) + " triangles (" +
                       (opts.ply_ascii ? "ASCII" : "binary") + " PLY)");
  }
  if (!opts.bt_path.empty()) {
    const OctoMapExportStats st = writeOctoMapBinary(map, *bt_out);
    messages.push_back("wrote " + opts.bt_path + ": OctoMap tree of " + std::to_string(st.nodes) + " nodes (" +
                       std::to_string(st.occupied_leaves) + " occupied and " + std::to_string(st.free_leaves) +
                       " free leaves)");
  }
  files.commit();
  for (const auto& m : messages) out << m << "\n";
  return 0;
}

void writeGzip(const void* data, std::size_t n, std::ostream& out) { gzip::compress(data, n, out); }

}  // namespace rtog::cli
