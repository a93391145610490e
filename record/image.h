// A linear RGB image and its PNG writer and reader (libpng; 8 bits per channel, written to a
// temporary name and renamed when complete).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace raycell {

struct Rgb {
  double r = 0, g = 0, b = 0;
};

class Image {
 public:
  Image(std::uint32_t width, std::uint32_t height)
      : width_(width), height_(height), pixels_(std::size_t(width) * height) {}
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  Rgb& at(std::uint32_t x, std::uint32_t y) { return pixels_[std::size_t(y) * width_ + x]; }
  const Rgb& at(std::uint32_t x, std::uint32_t y) const {
    return pixels_[std::size_t(y) * width_ + x];
  }
  const std::vector<Rgb>& pixels() const { return pixels_; }

 private:
  std::uint32_t width_, height_;
  std::vector<Rgb> pixels_;
};

// How 8-bit PNG values encode linear radiance (clamped to [0, 1], rounded to the nearest
// step of 1/255):
//  - kSrgb, the default of `raycell record`, for display: the sRGB transfer curve, and an
//    sRGB chunk saying so.
//  - kLinear: value * 255, and a gAMA chunk of 1.0 saying so. vdb_render writes the same
//    values (truncated rather than rounded) with no chunk, so viewers show both too dark.
enum class PngEncoding { kSrgb, kLinear };

// "srgb" or "linear"; InputError naming `what` otherwise.
PngEncoding ParsePngEncoding(const std::string& text, const std::string& what);
const char* ToString(PngEncoding e);

// Writes `image` as an 8-bit RGB PNG. Throws InputError naming the path on failure.
void WritePng(const Image& image, const std::string& path,
              PngEncoding encoding = PngEncoding::kSrgb);
// Reads an 8-bit RGB(A) or grey PNG back as linear RGB, decoding its values as `encoding`
// says whatever chunks the file holds (vdb_render's PNGs are linear and say nothing). For
// tests and accuracy benchmarks. InputError naming the path if it is not such a PNG.
Image ReadPng(const std::string& path, PngEncoding encoding);

// A PNG's 8-bit values as stored, converted to RGB as ReadPng converts them: row by row from
// the top, 3 bytes a pixel. What image comparisons measure on (the study's image RMSE).
struct Rgb8Image {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};
Rgb8Image ReadPng8(const std::string& path);

}  // namespace raycell
