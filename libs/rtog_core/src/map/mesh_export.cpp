#include "rtog/core/mesh_export.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <locale>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtog {
namespace {

// Corner v of a box: bit0 chooses max x, bit1 max y, bit2 max z. Two triangles per face,
// counter-clockwise seen from outside.
constexpr int kTriangles[12][3] = {
    {0, 4, 6}, {0, 6, 2},  // -x
    {1, 3, 7}, {1, 7, 5},  // +x
    {0, 1, 5}, {0, 5, 4},  // -y
    {2, 6, 7}, {2, 7, 3},  // +y
    {0, 2, 3}, {0, 3, 1},  // -z
    {4, 5, 7}, {4, 7, 6},  // +z
};

void putU32(std::string& buf, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) buf.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void putF32(std::string& buf, float f) {
  std::uint32_t u;
  static_assert(sizeof(u) == sizeof(f), "float must be 32-bit");
  std::memcpy(&u, &f, sizeof(u));
  putU32(buf, u);
}

}  // namespace

Rgb heightColor(double t) {
  if (!(t > 0.0)) t = 0.0;  // also NaN
  if (t > 1.0) t = 1.0;
  // Four linear segments through blue, cyan, green, yellow, red.
  const double s = t * 4.0;
  const int seg = std::min(3, static_cast<int>(s));
  const auto u = static_cast<std::uint8_t>(std::min(255.0, (s - seg) * 255.0 + 0.5));
  const auto d = static_cast<std::uint8_t>(255 - u);
  switch (seg) {
    case 0: return Rgb{0, u, 255};
    case 1: return Rgb{0, 255, d};
    case 2: return Rgb{u, 255, 0};
    default: return Rgb{255, d, 0};
  }
}

MeshExportStats writeOccupiedPly(const OccupancyMap& map, std::ostream& os, PlyEncoding encoding) {
  std::vector<Box> boxes;
  map.forEachLeaf([&](const Box& b, float v) {
    if (map.logOddsModel().classify(v) == CellState::Occupied) boxes.push_back(b);
  });
  if (boxes.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()) / 8)
    throw std::length_error("too many occupied cuboids (" + std::to_string(boxes.size()) +
                            ") for 32-bit PLY vertex indices");
  std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.min < b.min; });

  const Lattice& lat = map.lattice();
  double zmin = 0.0, zmax = 0.0;
  if (!boxes.empty()) {
    zmin = std::numeric_limits<double>::infinity();
    zmax = -zmin;
    for (const Box& b : boxes) {
      zmin = std::min(zmin, lat.boxMin(b).z());
      zmax = std::max(zmax, lat.boxMax(b).z());
    }
  }
  const double zspan = zmax - zmin;

  MeshExportStats st;
  st.cuboids = boxes.size();
  st.vertices = 8 * boxes.size();
  st.faces = 12 * boxes.size();

  const bool binary = encoding == PlyEncoding::BinaryLittleEndian;
  {
    std::ostringstream h;
    h.imbue(std::locale::classic());
    h << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
      << "comment rtog occupied cuboids, resolution " << map.resolution() << " m, colour by height\n"
      << "element vertex " << st.vertices << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << st.faces << "\n"
      << "property list uchar int vertex_indices\n"
      << "end_header\n";
    const std::string s = h.str();
    os.write(s.data(), static_cast<std::streamsize>(s.size()));
  }

  // Written in chunks of cuboids so memory stays small for large maps.
  constexpr std::size_t kChunk = 4096;
  std::string buf;
  std::ostringstream text;
  text.imbue(std::locale::classic());
  text.precision(std::numeric_limits<float>::max_digits10);
  auto flush = [&]() {
    if (binary) {
      os.write(buf.data(), static_cast<std::streamsize>(buf.size()));
      buf.clear();
    } else {
      const std::string s = text.str();
      os.write(s.data(), static_cast<std::streamsize>(s.size()));
      text.str(std::string());
    }
    if (!os) throw std::runtime_error("writing the PLY stream failed");
  };

  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const Eigen::Vector3d lo = lat.boxMin(boxes[i]), hi = lat.boxMax(boxes[i]);
    for (int v = 0; v < 8; ++v) {
      const float x = static_cast<float>((v & 1) ? hi.x() : lo.x());
      const float y = static_cast<float>((v & 2) ? hi.y() : lo.y());
      const double zd = (v & 4) ? hi.z() : lo.z();
      const float z = static_cast<float>(zd);
      const Rgb c = heightColor(zspan > 0.0 ? (zd - zmin) / zspan : 0.0);
      if (binary) {
        putF32(buf, x);
        putF32(buf, y);
        putF32(buf, z);
        buf.push_back(static_cast<char>(c.r));
        buf.push_back(static_cast<char>(c.g));
        buf.push_back(static_cast<char>(c.b));
      } else {
        text << x << ' ' << y << ' ' << z << ' ' << int{c.r} << ' ' << int{c.g} << ' ' << int{c.b} << '\n';
      }
    }
    if ((i + 1) % kChunk == 0) flush();
  }
  flush();
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const auto base = static_cast<std::uint32_t>(8 * i);
    for (const auto& t : kTriangles) {
      if (binary) {
        buf.push_back(3);
        for (int k = 0; k < 3; ++k) putU32(buf, base + static_cast<std::uint32_t>(t[k]));
      } else {
        text << "3 " << base + t[0] << ' ' << base + t[1] << ' ' << base + t[2] << '\n';
      }
    }
    if ((i + 1) % kChunk == 0) flush();
  }
  flush();
  return st;
}

}  // namespace rtog
