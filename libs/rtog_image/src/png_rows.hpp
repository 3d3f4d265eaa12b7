// Private to rtog_image: a PNG file written row by row (Picture::writePng), so that a picture is
// never held whole.
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>

namespace rtog::image {

class PngRows {
 public:
  /// Opens `path` for a width x height 8-bit BGR image; throws std::runtime_error if it cannot.
  PngRows(const std::string& path, int width, int height);
  ~PngRows();
  PngRows(const PngRows&) = delete;
  PngRows& operator=(const PngRows&) = delete;

  /// The next row: width BGR pixels.
  void write(const std::uint8_t* bgr);
  /// Ends the image after its last row and flushes the file; throws if it cannot be written.
  void close();

  struct State;

 private:
  std::unique_ptr<State> s_;
};

}  // namespace rtog::image
