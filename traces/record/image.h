// A linear RGB image and its PNG writer (libpng; 8-bit sRGB, written to a temporary name and
// renamed when complete).
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

// Writes `image` as an 8-bit sRGB PNG. Throws InputError naming the path on failure.
void WritePng(const Image& image, const std::string& path);
// Reads an 8-bit RGB(A) PNG back as linear RGB (for tests and accuracy benchmarks).
Image ReadPng(const std::string& path);

}  // namespace raycell
