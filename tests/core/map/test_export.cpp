// Exports of real maps read back by other tools' rules: the OctoMap .bt by liboctomap itself,
// the PLY by its header and body layout, the PNG slice pixel by pixel against the map.
#include <gtest/gtest.h>

#include <octomap/OcTree.h>
#include <opencv2/core.hpp>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "rtog/core/mesh_export.hpp"
#include "rtog/core/octomap_export.hpp"
#include "rtog/image/slice.hpp"
#include "test_support.hpp"

using namespace rtog;

namespace {

OccupancyMap buildTumMap(double resolution, MergePolicy merge, int stride) {
  MapParams p;
  p.resolution = resolution;
  p.merge = merge;
  OccupancyMap map(p);
  for (const auto& s : test::loadTumScans(stride)) map.insertPointCloud(s.origin, s.points);
  return map;
}

// Built once: the TUM frames at 5 cm with merging (large cuboids) and at 10 cm without.
const OccupancyMap& mergedMap() {
  static const OccupancyMap m = buildTumMap(0.05, MergePolicy::Equal, 4);
  return m;
}
const OccupancyMap& unmergedMap() {
  static const OccupancyMap m = buildTumMap(0.1, MergePolicy::Off, 4);
  return m;
}

std::string tempPath(const std::string& name) { return ::testing::TempDir() + "/rtog_export_" + name; }

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---- OctoMap .bt ------------------------------------------------------------------------

CellState octoState(const octomap::OcTree& tree, const Key& k) {
  const octomap::OcTreeKey ok(static_cast<octomap::key_type>(k.x + kOctoMapKeyOffset),
                              static_cast<octomap::key_type>(k.y + kOctoMapKeyOffset),
                              static_cast<octomap::key_type>(k.z + kOctoMapKeyOffset));
  const octomap::OcTreeNode* n = tree.search(ok);
  if (!n) return CellState::Unknown;
  return tree.isNodeOccupied(n) ? CellState::Occupied : CellState::Free;
}

/// Writes the map as .bt, reads it with liboctomap and compares the class of every known cell
/// and of the unknown cells in the bounds grown by two cells (every `unknown_step`-th cell).
void checkBtRoundTrip(const OccupancyMap& map, const std::string& name, int unknown_step) {
  const std::string path = tempPath(name + ".bt");
  OctoMapExportStats st;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    st = writeOctoMapBinary(map, out);
    ASSERT_TRUE(out.good());
  }
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path)) << "liboctomap refused " << path;
  EXPECT_EQ(tree.getResolution(), map.resolution());
  EXPECT_EQ(tree.size(), st.nodes);
  EXPECT_EQ(st.nodes, st.inner_nodes + st.occupied_leaves + st.free_leaves);

  std::int64_t cells = 0, mismatches = 0;
  map.forEachLeaf([&](const Box& b, float v) {
    const CellState want = map.logOddsModel().classify(v);
    forEachCell(b, [&](const Key& k) {
      ++cells;
      mismatches += octoState(tree, k) != want;
    });
  });
  EXPECT_EQ(cells, map.cellCount());
  EXPECT_EQ(mismatches, 0) << "known cells whose class differs in OctoMap";

  // Unknown cells: the bounds grown by two cells, or for maps spread too wide for that, the
  // 5x5x5 neighbourhoods of every leaf's corners.
  const Box bounds = map.keyBounds();
  const Box grown{Key{bounds.min.x - 2, bounds.min.y - 2, bounds.min.z - 2},
                  Key{bounds.max.x + 2, bounds.max.y + 2, bounds.max.z + 2}};
  std::int64_t unknown = 0, checked = 0, wrong = 0;
  const auto check = [&](const Key& k) {
    const CellState s = map.state(k);
    ++checked;
    unknown += s == CellState::Unknown;
    wrong += octoState(tree, k) != s;
  };
  if (grown.volume() <= 50'000'000) {
    forEachCell(grown, [&](const Key& k) {
      if ((k.x + k.y + k.z) % unknown_step == 0) check(k);
    });
  } else {
    map.forEachLeaf([&](const Box& b, float) {
      for (const Key& c : {b.min, b.max})
        forEachCell(Box{Key{c.x - 2, c.y - 2, c.z - 2}, Key{c.x + 2, c.y + 2, c.z + 2}}, [&](const Key& k) {
          if (inOctoMapKeyRange(Box::cell(k))) check(k);
        });
    });
  }
  EXPECT_GT(unknown, std::min<std::int64_t>(1000, checked / 2));
  EXPECT_EQ(wrong, 0) << "of " << checked << " cells in the bounds (" << unknown << " unknown)";

  // Same bytes as OctoMap's own writer produces for the tree it read (it is already pruned).
  std::ostringstream again;
  ASSERT_TRUE(tree.writeBinaryConst(again));
  const std::string ours = readAll(path), theirs = again.str();
  const auto data_of = [](const std::string& s) { return s.substr(s.find("\ndata\n") + 6); };
  EXPECT_TRUE(data_of(ours) == data_of(theirs)) << "tree stream differs from liboctomap's";
  std::cout << "[ export ] " << name << ": " << cells << " cells -> " << st.nodes << " OctoMap nodes ("
            << st.occupied_leaves << " occupied, " << st.free_leaves << " free leaves), " << ours.size()
            << " bytes\n";
}

TEST(OctoMapExport, MergedTumMapReadsBackWithLiboctomap) { checkBtRoundTrip(mergedMap(), "merged", 3); }
TEST(OctoMapExport, UnmergedTumMapReadsBackWithLiboctomap) { checkBtRoundTrip(unmergedMap(), "unmerged", 1); }

TEST(OctoMapExport, EmptyMapIsAnEmptyTree) {
  const OccupancyMap map;
  std::ostringstream out;
  const OctoMapExportStats st = writeOctoMapBinary(map, out);
  EXPECT_EQ(st.nodes, 0u);
  std::istringstream in(out.str());
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(in));
  EXPECT_EQ(tree.size(), 0u);
  EXPECT_EQ(tree.getResolution(), 0.05);
}

TEST(OctoMapExport, CellsAtTheKeyRangeEdgesAndBeyond) {
  MapParams p;
  p.resolution = 0.1;
  InsertParams ip;
  ip.model = SensorModel::BeamEndPoint;
  // The extreme cells OctoMap has (keys -32768 and 32767 per axis) export and read back.
  OccupancyMap edge(p);
  const std::vector<Eigen::Vector3f> corners = {Eigen::Vector3f(-3276.75f, -3276.75f, -3276.75f),
                                                Eigen::Vector3f(3276.75f, 3276.75f, 3276.75f),
                                                Eigen::Vector3f(-3276.75f, 3276.75f, 0.05f)};
  edge.insertPointCloud(Eigen::Vector3d(0.05, 0.05, 0.05), corners, ip);
  ASSERT_EQ(edge.leafCount(), 3u);
  checkBtRoundTrip(edge, "edges", 1);

  // One cell past the range: a clear error and nothing written.
  OccupancyMap beyond(p);
  beyond.insertPointCloud(Eigen::Vector3d(0.05, 0.05, 0.05), {Eigen::Vector3f(3276.85f, 0.05f, 0.05f)}, ip);
  std::ostringstream out;
  try {
    writeOctoMapBinary(beyond, out);
    FAIL() << "no error for a cell outside OctoMap's key range";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("outside OctoMap's key range"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(out.str().empty());
}

// ---- PLY ----------------------------------------------------------------------------------

struct PlyHeader {
  std::string format;
  std::int64_t vertices = -1, faces = -1;
  std::vector<std::string> vertex_props;
  std::string face_prop;
  std::size_t body = 0;  // offset of the first byte after end_header
};

PlyHeader parsePlyHeader(const std::string& file) {
  PlyHeader h;
  std::istringstream in(file);
  std::string line, element;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      ls >> h.format;
    } else if (word == "element") {
      std::int64_t n = 0;
      ls >> element >> n;
      (element == "vertex" ? h.vertices : h.faces) = n;
    } else if (word == "property") {
      if (element == "vertex") h.vertex_props.push_back(line.substr(9));
      else h.face_prop = line.substr(9);
    } else if (word == "end_header") {
      h.body = static_cast<std::size_t>(in.tellg());
      break;
    }
  }
  return h;
}

struct Vertex {
  float x, y, z;
  std::uint8_t rgb[3];
};

/// Checks the layout and returns the vertices and triangles of either encoding.
void readPly(const std::string& file, const PlyHeader& h, std::vector<Vertex>& v, std::vector<std::array<int, 3>>& f) {
  v.resize(static_cast<std::size_t>(h.vertices));
  f.resize(static_cast<std::size_t>(h.faces));
  if (h.format == "binary_little_endian") {
    ASSERT_EQ(file.size(), h.body + v.size() * 15 + f.size() * 13);
    const char* p = file.data() + h.body;
    for (auto& q : v) {
      std::memcpy(&q.x, p, 4);  // the test machine is little-endian like the file
      std::memcpy(&q.y, p + 4, 4);
      std::memcpy(&q.z, p + 8, 4);
      std::memcpy(q.rgb, p + 12, 3);
      p += 15;
    }
    for (auto& t : f) {
      ASSERT_EQ(*p, 3);
      std::memcpy(t.data(), p + 1, 12);
      p += 13;
    }
  } else {
    ASSERT_EQ(h.format, "ascii");
    std::istringstream in(file.substr(h.body));
    for (auto& q : v) {
      int r, g, b;
      in >> q.x >> q.y >> q.z >> r >> g >> b;
      q.rgb[0] = std::uint8_t(r), q.rgb[1] = std::uint8_t(g), q.rgb[2] = std::uint8_t(b);
    }
    for (auto& t : f) {
      int n;
      in >> n >> t[0] >> t[1] >> t[2];
      ASSERT_EQ(n, 3);
    }
    ASSERT_TRUE(in.good());
    std::string rest;
    in >> rest;
    EXPECT_TRUE(rest.empty()) << "trailing data";
  }
}

void checkPly(const OccupancyMap& map, PlyEncoding enc) {
  std::ostringstream out;
  const MeshExportStats st = writeOccupiedPly(map, out, enc);
  const std::string file = out.str();
  const PlyHeader h = parsePlyHeader(file);
  const std::size_t occupied = map.statistics().occupied_leaves;
  ASSERT_GT(occupied, 1000u);
  EXPECT_EQ(st.cuboids, occupied);
  EXPECT_EQ(h.vertices, static_cast<std::int64_t>(8 * occupied));
  EXPECT_EQ(h.faces, static_cast<std::int64_t>(12 * occupied));
  EXPECT_EQ(h.format, enc == PlyEncoding::Ascii ? "ascii" : "binary_little_endian");
  EXPECT_EQ(h.vertex_props, (std::vector<std::string>{"float x", "float y", "float z", "uchar red", "uchar green",
                                                       "uchar blue"}));
  EXPECT_EQ(h.face_prop, "list uchar int vertex_indices");

  std::vector<Vertex> v;
  std::vector<std::array<int, 3>> f;
  readPly(file, h, v, f);
  if (::testing::Test::HasFatalFailure()) return;

  // Every group of 8 vertices spans exactly one occupied leaf; the 12 triangles of a group
  // use only its vertices, cover its 6 faces and face outwards.
  std::map<std::tuple<float, float, float, float, float, float>, int> want;
  map.forEachLeaf([&](const Box& b, float val) {
    if (map.logOddsModel().classify(val) != CellState::Occupied) return;
    const Eigen::Vector3d lo = map.lattice().boxMin(b), hi = map.lattice().boxMax(b);
    ++want[{float(lo.x()), float(lo.y()), float(lo.z()), float(hi.x()), float(hi.y()), float(hi.z())}];
  });
  std::int64_t bad_boxes = 0, bad_faces = 0;
  for (std::size_t c = 0; c < occupied; ++c) {
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo, centre = Eigen::Vector3f::Zero();
    for (int k = 0; k < 8; ++k) {
      const Vertex& q = v[8 * c + k];
      const Eigen::Vector3f p(q.x, q.y, q.z);
      lo = lo.cwiseMin(p), hi = hi.cwiseMax(p), centre += p / 8.0f;
    }
    auto it = want.find({lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()});
    if (it == want.end() || it->second == 0) ++bad_boxes;
    else --it->second;
    for (int t = 0; t < 12; ++t) {
      const auto& tri = f[12 * c + t];
      bool inside = true;
      for (int k : tri) inside = inside && k >= int(8 * c) && k < int(8 * c + 8);
      if (!inside) {
        ++bad_faces;
        continue;
      }
      const auto P = [&](int k) { return Eigen::Vector3f(v[k].x, v[k].y, v[k].z); };
      const Eigen::Vector3f n = (P(tri[1]) - P(tri[0])).cross(P(tri[2]) - P(tri[0]));
      if (!(n.norm() > 0.0f) || n.dot(P(tri[0]) - centre) <= 0.0f) ++bad_faces;
    }
  }
  EXPECT_EQ(bad_boxes, 0) << "vertex groups that are not an occupied leaf";
  EXPECT_EQ(bad_faces, 0) << "triangles outside their cuboid, degenerate or facing inwards";

  // Colour by height: the lowest vertices blue, the highest red.
  const auto [lo_it, hi_it] =
      std::minmax_element(v.begin(), v.end(), [](const Vertex& a, const Vertex& b) { return a.z < b.z; });
  EXPECT_EQ(int(lo_it->rgb[2]), 255);
  EXPECT_EQ(int(lo_it->rgb[0]), 0);
  EXPECT_EQ(int(hi_it->rgb[0]), 255);
  EXPECT_EQ(int(hi_it->rgb[2]), 0);
}

TEST(PlyExport, BinaryMeshOfMergedMap) { checkPly(mergedMap(), PlyEncoding::BinaryLittleEndian); }
TEST(PlyExport, AsciiMeshOfUnmergedMap) { checkPly(unmergedMap(), PlyEncoding::Ascii); }

TEST(PlyExport, EmptyMapIsAValidEmptyMesh) {
  std::ostringstream out;
  const MeshExportStats st = writeOccupiedPly(OccupancyMap(), out);
  EXPECT_EQ(st.vertices, 0u);
  const PlyHeader h = parsePlyHeader(out.str());
  EXPECT_EQ(h.vertices, 0);
  EXPECT_EQ(h.faces, 0);
  EXPECT_EQ(h.body, out.str().size());
}

// ---- PNG slice ------------------------------------------------------------------------------

void checkSlice(const OccupancyMap& map, double z) {
  const cv::Mat img = image::rasterizeSliceZ(map, z);
  const Box b = map.keyBounds();
  ASSERT_EQ(img.type(), CV_8UC1);
  ASSERT_EQ(img.cols, b.extent(0));
  ASSERT_EQ(img.rows, b.extent(1));
  const std::int32_t kz = map.lattice().key(Eigen::Vector3d(0, 0, z)).z;
  std::int64_t counts[3] = {0, 0, 0}, wrong = 0;
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) {
      const CellState s = map.state(Key{b.min.x + c, b.max.y - r, kz});
      const std::uint8_t want = s == CellState::Occupied ? image::kSliceOccupied
                                : s == CellState::Free   ? image::kSliceFree
                                                         : image::kSliceUnknown;
      ++counts[int(s)];
      wrong += img.at<std::uint8_t>(r, c) != want;
    }
  EXPECT_EQ(wrong, 0) << "pixels differing from map.state() at z = " << z;
  EXPECT_GT(counts[int(CellState::Occupied)], 10) << "z = " << z;
  EXPECT_GT(counts[int(CellState::Free)], 100) << "z = " << z;
  EXPECT_GT(counts[int(CellState::Unknown)], 100) << "z = " << z;
}

TEST(SliceExport, EveryPixelMatchesTheMap) {
  for (double z : {0.0, 0.3, 0.77, 1.5}) {
    checkSlice(mergedMap(), z);
    checkSlice(unmergedMap(), z);
  }
}

// The probability slice: known pixels grey 255 * (1 - P) of the cell, unknown ones the marker colour.
TEST(SliceExport, ProbabilitySliceShowsEachCellsProbability) {
  for (const OccupancyMap* map : {&mergedMap(), &unmergedMap()}) {
    const double z = 0.3;
    const cv::Mat img = image::rasterizeSliceProbabilityZ(*map, z);
    const Box b = map->keyBounds();
    ASSERT_EQ(img.type(), CV_8UC3);
    ASSERT_EQ(img.cols, b.extent(0));
    ASSERT_EQ(img.rows, b.extent(1));
    const std::int32_t kz = map->lattice().key(Eigen::Vector3d(0, 0, z)).z;
    std::int64_t wrong = 0, known = 0, unknown = 0;
    for (int r = 0; r < img.rows; ++r)
      for (int c = 0; c < img.cols; ++c) {
        const Key k{b.min.x + c, b.max.y - r, kz};
        const cv::Vec3b px = img.at<cv::Vec3b>(r, c);
        if (const auto l = map->logOdds(k)) {
          const auto g = static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - map->occupancy(k))));
          wrong += px != cv::Vec3b(g, g, g);
          ++known;
        } else {
          wrong += px != cv::Vec3b(image::kSliceUnknownColour[0], image::kSliceUnknownColour[1], image::kSliceUnknownColour[2]);
          ++unknown;
        }
      }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(known, 100);
    EXPECT_GT(unknown, 100);
  }
  EXPECT_THROW(image::rasterizeSliceProbabilityZ(OccupancyMap(), 0.0), std::invalid_argument);
}

TEST(SliceExport, BadInput) {
  EXPECT_THROW(image::rasterizeSliceZ(OccupancyMap(), 0.0), std::invalid_argument);
  EXPECT_THROW(image::rasterizeSliceZ(mergedMap(), std::nan("")), std::invalid_argument);
  EXPECT_THROW(image::rasterizeSliceZ(mergedMap(), 1e12), std::invalid_argument);
  const cv::Mat above = image::rasterizeSliceZ(mergedMap(), 50.0);  // no cells up there
  EXPECT_EQ(cv::countNonZero(above != image::kSliceUnknown), 0);
}

}  // namespace
