#include "traces/record/image.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "base/check.h"
#include "base/file.h"

namespace raycell {
namespace {

std::uint8_t ToSrgb8(double linear) {
  if (!(linear > 0)) return 0;  // also maps NaN to black; the renderer never produces NaN
  const double v =
      linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
  return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
}

double FromSrgb8(std::uint8_t v) {
  const double s = v / 255.0;
  return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

void AppendPngBytes(png_structp png, png_bytep data, png_size_t size) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), size);
}

}  // namespace

void WritePng(const Image& image, const std::string& path) {
  // Encoded in memory, then written through base's atomic write.
  std::string bytes;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw InputError(path + ": PNG encoding failed");
  }
  png_set_write_fn(png, &bytes, AppendPngBytes, nullptr);
  png_set_IHDR(png, info, image.width(), image.height(), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  std::vector<std::uint8_t> row(std::size_t(image.width()) * 3);
  for (std::uint32_t y = 0; y < image.height(); ++y) {
    for (std::uint32_t x = 0; x < image.width(); ++x) {
      const Rgb& p = image.at(x, y);
      row[3 * x] = ToSrgb8(p.r);
      row[3 * x + 1] = ToSrgb8(p.g);
      row[3 * x + 2] = ToSrgb8(p.b);
    }
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  WriteFileAtomically(path, bytes);
}

Image ReadPng(const std::string& path) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str())) {
    throw InputError(path + ": not a readable PNG: " + img.message);
  }
  img.format = PNG_FORMAT_RGB;
  std::vector<std::uint8_t> buf(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, buf.data(), 0, nullptr)) {
    throw InputError(path + ": PNG decode failed: " + img.message);
  }
  Image out(img.width, img.height);
  for (std::uint32_t y = 0; y < img.height; ++y) {
    for (std::uint32_t x = 0; x < img.width; ++x) {
      const std::uint8_t* p = &buf[(std::size_t(y) * img.width + x) * 3];
      out.at(x, y) = {FromSrgb8(p[0]), FromSrgb8(p[1]), FromSrgb8(p[2])};
    }
  }
  return out;
}

}  // namespace raycell
