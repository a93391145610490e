#include "record/image.h"

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

std::uint8_t ToLinear8(double linear) {
  if (!(linear > 0)) return 0;
  return static_cast<std::uint8_t>(std::lround(std::min(linear, 1.0) * 255.0));
}

double FromSrgb8(std::uint8_t v) {
  const double s = v / 255.0;
  return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

double FromLinear8(std::uint8_t v) { return v / 255.0; }

void AppendPngBytes(png_structp png, png_bytep data, png_size_t size) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), size);
}

// libpng reports read errors by longjmp: the two functions that call it hold no C++ object
// that a jump would skip.
struct PngRead {
  FILE* file = nullptr;
  png_structp png = nullptr;
  png_infop info = nullptr;
  png_uint_32 width = 0, height = 0;
  ~PngRead() {
    png_destroy_read_struct(&png, &info, nullptr);
    if (file) std::fclose(file);
  }
};

// Reads the header and sets the transforms to 8-bit RGB; false if that is not possible.
bool ReadPngInfo(PngRead* r) {
  r->png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!r->png) return false;
  r->info = png_create_info_struct(r->png);
  if (!r->info || setjmp(png_jmpbuf(r->png))) return false;
  png_init_io(r->png, r->file);
  png_read_info(r->png, r->info);
  png_set_strip_16(r->png);
  png_set_strip_alpha(r->png);
  png_set_palette_to_rgb(r->png);
  png_set_expand_gray_1_2_4_to_8(r->png);
  png_set_gray_to_rgb(r->png);
  png_read_update_info(r->png, r->info);
  r->width = png_get_image_width(r->png, r->info);
  r->height = png_get_image_height(r->png, r->info);
  return png_get_rowbytes(r->png, r->info) == std::size_t(r->width) * 3;
}

bool ReadPngRows(PngRead* r, png_bytep* rows) {
  if (setjmp(png_jmpbuf(r->png))) return false;
  png_read_image(r->png, rows);
  png_read_end(r->png, nullptr);
  return true;
}

}  // namespace

PngEncoding ParsePngEncoding(const std::string& text, const std::string& what) {
  if (text == "srgb") return PngEncoding::kSrgb;
  if (text == "linear") return PngEncoding::kLinear;
  throw InputError(what + " '" + text + "': expected srgb or linear");
}

const char* ToString(PngEncoding e) { return e == PngEncoding::kSrgb ? "srgb" : "linear"; }

void WritePng(const Image& image, const std::string& path, PngEncoding encoding) {
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
  const bool srgb = encoding == PngEncoding::kSrgb;
  if (srgb) {
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  } else {
    png_set_gAMA(png, info, 1.0);
  }
  png_write_info(png, info);
  std::vector<std::uint8_t> row(std::size_t(image.width()) * 3);
  for (std::uint32_t y = 0; y < image.height(); ++y) {
    for (std::uint32_t x = 0; x < image.width(); ++x) {
      const Rgb& p = image.at(x, y);
      row[3 * x] = srgb ? ToSrgb8(p.r) : ToLinear8(p.r);
      row[3 * x + 1] = srgb ? ToSrgb8(p.g) : ToLinear8(p.g);
      row[3 * x + 2] = srgb ? ToSrgb8(p.b) : ToLinear8(p.b);
    }
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  WriteFileAtomically(path, bytes);
}

Rgb8Image ReadPng8(const std::string& path) {
  PngRead r;
  r.file = std::fopen(path.c_str(), "rb");
  if (!r.file) throw InputError(path + ": cannot open the PNG");
  if (!ReadPngInfo(&r)) throw InputError(path + ": not a readable 8-bit PNG");
  Rgb8Image out{r.width, r.height, std::vector<std::uint8_t>(std::size_t(r.width) * r.height * 3)};
  std::vector<png_bytep> rows(r.height);
  for (std::size_t y = 0; y < rows.size(); ++y) rows[y] = &out.rgb[y * std::size_t(r.width) * 3];
  if (!ReadPngRows(&r, rows.data())) throw InputError(path + ": PNG decode failed");
  return out;
}

Image ReadPng(const std::string& path, PngEncoding encoding) {
  const Rgb8Image png = ReadPng8(path);
  Image out(png.width, png.height);
  const auto decode = encoding == PngEncoding::kSrgb ? FromSrgb8 : FromLinear8;
  for (std::uint32_t y = 0; y < png.height; ++y) {
    for (std::uint32_t x = 0; x < png.width; ++x) {
      const std::uint8_t* p = &png.rgb[(std::size_t(y) * png.width + x) * 3];
      out.at(x, y) = {decode(p[0]), decode(p[1]), decode(p[2])};
    }
  }
  return out;
}

}  // namespace raycell
