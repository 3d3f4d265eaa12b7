// PNG encoding with libpng rather than OpenCV's imencode/imwrite: OpenCV registers every codec
// it was built with on its first encode, and Debian's build registers GDAL's drivers then, which
// pages about 9 MB of libgdal into the process. An MRPT app saving our map at the end of its
// run, when it holds the most, would pay that in its peak RSS for one picture.
#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "png_rows.hpp"
#include "rtog/image/picture.hpp"

namespace rtog::image {
namespace {

/// libpng's write state, destroyed however encoding ends.
struct PngWriter {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::string error;
  PngWriter() {
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, this, &PngWriter::onError, &PngWriter::onWarning);
    if (png) info = png_create_info_struct(png);
    if (!png || !info) {
      png_destroy_write_struct(&png, &info);
      throw std::runtime_error("cannot encode a PNG: out of memory");
    }
  }
  ~PngWriter() { png_destroy_write_struct(&png, &info); }
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;

  static void onError(png_structp p, png_const_charp msg) {
    static_cast<PngWriter*>(png_get_error_ptr(p))->error = msg;
    png_longjmp(p, 1);
  }
  static void onWarning(png_structp, png_const_charp) {}
};

/// libpng's output function for a sink with append(data, n).
template <class Sink>
void writeToSink(png_structp p, png_bytep data, png_size_t n) {
  bool stored = true;
  try {
    static_cast<Sink*>(png_get_io_ptr(p))->append(reinterpret_cast<const char*>(data), n);
  } catch (...) {  // no exception may cross libpng's C frames
    stored = false;
  }
  if (!stored) png_error(p, "cannot store the encoded bytes");
}

void header(png_structp png, png_infop info, int width, int height, bool grey, int level) {
  png_set_compression_level(png, level);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8,
               grey ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (!grey) png_set_bgr(png);
}

/// The bytes of `image` (8-bit, 1 channel grey or 3 channels BGR) to `sink`.
template <class Sink>
void encode(const cv::Mat& image, int level, Sink& sink) {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3) || image.empty())
    throw std::invalid_argument("cannot encode a PNG: the image is not 8-bit grey or BGR, or is empty");
  PngWriter w;
  // No C++ object with a destructor may be created between setjmp and the last libpng call.
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
  for (int r = 0; r < image.rows; ++r) rows[static_cast<std::size_t>(r)] = const_cast<png_bytep>(image.ptr<png_byte>(r));
  if (setjmp(png_jmpbuf(w.png))) throw std::runtime_error("cannot encode a PNG: " + w.error);
  png_set_write_fn(w.png, &sink, writeToSink<Sink>, nullptr);
  header(w.png, w.info, image.cols, image.rows, image.channels() == 1, level);
  png_write_image(w.png, rows.data());
  png_write_end(w.png, nullptr);
}

struct FileSink {
  std::ofstream& os;
  void append(const char* data, std::size_t n) { os.write(data, static_cast<std::streamsize>(n)); }
};

}  // namespace

struct PngRows::State {
  std::ofstream os;
  FileSink sink{os};
  PngWriter w;
  std::string path;
};

PngRows::PngRows(const std::string& path, int width, int height) : s_(std::make_unique<State>()) {
  s_->path = path;
  s_->os.open(path, std::ios::binary);
  if (!s_->os) throw std::runtime_error("cannot open '" + path + "' for writing");
  if (width <= 0 || height <= 0) throw std::invalid_argument("cannot encode a PNG: the image is empty");
  png_structp png = s_->w.png;
  if (setjmp(png_jmpbuf(png))) throw std::runtime_error("cannot encode a PNG: " + s_->w.error);
  png_set_write_fn(png, &s_->sink, writeToSink<FileSink>, nullptr);
  header(png, s_->w.info, width, height, false, 6);
}

PngRows::~PngRows() = default;

void PngRows::write(const std::uint8_t* bgr) {
  png_structp png = s_->w.png;
  if (setjmp(png_jmpbuf(png))) throw std::runtime_error("cannot encode a PNG: " + s_->w.error);
  png_write_row(png, const_cast<png_bytep>(bgr));
}

void PngRows::close() {
  png_structp png = s_->w.png;
  if (setjmp(png_jmpbuf(png))) throw std::runtime_error("cannot encode a PNG: " + s_->w.error);
  png_write_end(png, nullptr);
  s_->os.flush();
  if (!s_->os) throw std::runtime_error("cannot write '" + s_->path + "'");
}

std::string encodePng(const cv::Mat& image) {
  std::string bytes;
  encode(image, 9, bytes);
  return bytes;
}

void writePng(const std::string& path, const cv::Mat& image) {
  std::ofstream os(path, std::ios::binary);
  if (!os) throw std::runtime_error("cannot open '" + path + "' for writing");
  FileSink sink{os};
  encode(image, 6, sink);
  os.flush();
  if (!os) throw std::runtime_error("cannot write '" + path + "'");
}

}  // namespace rtog::image
