// rtog.Band and rtog.image: a height band of the map as an image of probabilities, and the image
// operations of the estimator seed on it (threshold, blur, morphology, Hough, regions, polar).
#include <vector>

#include "py_map.hpp"
#include "rtog/image/grid_ops.hpp"

namespace rtog::python {
namespace {

/// A mask as OpenCV takes it: uint8 (H, W), read in place.
cv::Mat maskMat(const ByteArray& mask) {
  if (mask.ndim() != 2) throw pyb::value_error("mask: expected a uint8 (H, W) image");
  return cv::Mat(int(mask.shape(0)), int(mask.shape(1)), CV_8U, const_cast<std::uint8_t*>(mask.data()));
}

}  // namespace

void bindImage(pyb::module_& m) {
  pyb::class_<image::GridImage>(m, "Band", R"doc(
A height band of a map as an image (Map.band): `p` is P(occupied) per column (float32 (H, W), NaN
unknown), row 0 the highest y; pixel (r, c) is the column of lattice key (x0 + c, y0 + H - 1 - r).
)doc")
      .def_property_readonly("p", [](const image::GridImage& g) { return matArray(g.p); }, "P(occupied), NaN unknown.")
      .def_readonly("x0", &image::GridImage::x0)
      .def_readonly("y0", &image::GridImage::y0)
      .def_readonly("resolution", &image::GridImage::resolution)
      .def(
          "to_metres",
          [](const image::GridImage& g, double column, double row) {
            const Eigen::Vector2d v = g.toMetres(column, row);
            return pyb::make_tuple(v.x(), v.y());
          },
          pyb::arg("column"), pyb::arg("row"), "The map coordinates [m] of a pixel's centre.");

  pyb::class_<PyMap, std::shared_ptr<PyMap>>(m.attr("Map")).def(
      "band",
      [](const PyMap& self, double zmin, double zmax) {
        return self.read([&](const CRTreeOccupancyGridMap& map) { return image::bandImage(map.map(), zmin, zmax); });
      },
      pyb::arg("zmin"), pyb::arg("zmax"),
      "The columns over [zmin, zmax] [m] (each its highest log-odds, as the 2D view) as an rtog.Band.");

  auto im = m.def_submodule("image", "Image operations on a map's height band (rtog.Band), through OpenCV.");
  im.def(
      "threshold", [](const image::GridImage& g, double p) { return matArray(image::threshold(g, p)); },
      pyb::arg("band"), pyb::arg("p"), "uint8 mask: 255 where P >= p (unknown pixels 0).");
  im.def(
      "blur",
      [](const image::GridImage& g, double sigma) {
        pyb::gil_scoped_release nogil;
        return image::blur(g, sigma);
      },
      pyb::arg("band"), pyb::arg("sigma"),
      "The band blurred by a Gaussian of sigma [m], unknown pixels left out of the weights and unknown after.");
  im.def(
      "blur_with_prior",
      [](const image::GridImage& g, double sigma, double prior) {
        pyb::gil_scoped_release nogil;
        return image::blurWithPrior(g, sigma, prior);
      },
      pyb::arg("band"), pyb::arg("sigma"), pyb::arg("prior") = 0.5,
      "The blur of pose uncertainty: unknown pixels count as `prior`, the band widened by 3 sigma.");
  im.def(
      "open", [](const ByteArray& mask, int k) { return matArray(image::open(maskMat(mask), k)); }, pyb::arg("mask"),
      pyb::arg("k"), "Morphological opening by a k x k square (k odd).");
  im.def(
      "close", [](const ByteArray& mask, int k) { return matArray(image::close(maskMat(mask), k)); }, pyb::arg("mask"),
      pyb::arg("k"), "Morphological closing by a k x k square (k odd).");
  im.def(
      "hough_segments",
      [](const ByteArray& mask, const image::GridImage& geometry, double min_length, double max_gap) {
        const auto segs = image::houghSegments(maskMat(mask), geometry, min_length, max_gap);
        pyb::array_t<double> out({static_cast<pyb::ssize_t>(segs.size()), pyb::ssize_t{4}});
        for (std::size_t i = 0; i < segs.size(); ++i) {
          const auto& s = segs[i];
          const double row[4] = {s.a.x(), s.a.y(), s.b.x(), s.b.y()};
          for (int c = 0; c < 4; ++c) out.mutable_at(pyb::ssize_t(i), c) = row[c];
        }
        return out;
      },
      pyb::arg("mask"), pyb::arg("band"), pyb::arg("min_length"), pyb::arg("max_gap"),
      "Straight walls of a mask as segments (K, 4): x0, y0, x1, y1 [m], longest first.");
  im.def(
      "connected_regions",
      [](const ByteArray& mask) {
        cv::Mat labels;
        std::vector<int> areas;
        image::connectedRegions(maskMat(mask), labels, areas);
        return pyb::make_tuple(matArray(labels), pyb::array_t<int>(static_cast<pyb::ssize_t>(areas.size()), areas.data()));
      },
      pyb::arg("mask"), "8-connected regions: (labels int32 (H, W), 0 the background; area per label).");
  im.def(
      "polar_to_cartesian",
      [](const FloatArray& ranges, double aperture, double max_range, double resolution) {
        const std::vector<float> r(ranges.data(), ranges.data() + ranges.size());
        return matArray(image::polarToCartesian(r, aperture, max_range, resolution));
      },
      pyb::arg("ranges"), pyb::arg("aperture"), pyb::arg("max_range"), pyb::arg("resolution"),
      "A scan's ranges as a uint8 image centred on the sensor, 255 at the end points.");
  im.def(
      "cartesian_to_polar",
      [](const ByteArray& image, std::size_t beams, double aperture, double max_range, double resolution) {
        const auto r = image::cartesianToPolar(maskMat(image), beams, aperture, max_range, resolution);
        return pyb::array_t<float>(static_cast<pyb::ssize_t>(r.size()), r.data());
      },
      pyb::arg("image"), pyb::arg("beams"), pyb::arg("aperture"), pyb::arg("max_range"), pyb::arg("resolution"),
      "For each of `beams` angles the range to the first pixel >= 128 (0 where none).");
}

}  // namespace rtog::python
