// SPDX-License-Identifier: BSD-3-Clause
// render/src/png_io.cpp -- PNG encode/decode and image comparison helpers
#include <png.h>

#include <cerrno>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <unistd.h>

#include "penumbra/core/error.h"
#include "penumbra/render/image.h"

namespace penumbra::render {
namespace {

[[noreturn]] void io_fail(const std::string& what, const std::string& path) {
  throw Error(ErrorCode::io_error, what + " '" + path + "': " + std::strerror(errno));
}

// libpng reports errors through longjmp; this handler turns them into a flag the caller checks.
void png_error_handler(png_structp png, png_const_charp msg) {
  auto* text = static_cast<std::string*>(png_get_error_ptr(png));
  if (text) *text = msg;
  png_longjmp(png, 1);
}
void png_warning_handler(png_structp, png_const_charp) {}

// Appends what libpng writes to the std::vector<unsigned char> its io pointer names.
void append_to_vector(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}
void no_flush(png_structp) {}

// Encodes into `f`, or, with `f` null, into `memory`.
bool encode(std::FILE* f, std::vector<unsigned char>* memory, const std::vector<unsigned char>& rgb, int w, int h,
            std::string& err) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &err, png_error_handler, png_warning_handler);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  if (f) png_init_io(png, f);
  else png_set_write_fn(png, memory, append_to_vector, no_flush);
  // Speed over size: image databases are written every step inside the solver's loop.
  png_set_compression_level(png, 3);
  png_set_IHDR(png, info, static_cast<png_uint_32>(w), static_cast<png_uint_32>(h), 8, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < h; ++y) png_write_row(png, rgb.data() + static_cast<std::size_t>(y) * w * 3);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

std::vector<unsigned char> to_rgb8(const Image& image, const float background[3]) {
  std::vector<unsigned char> out(static_cast<std::size_t>(image.width) * image.height * 3);
  for (std::size_t i = 0, n = out.size() / 3; i < n; ++i) {
    const float* p = &image.rgba[i * 4];
    for (int c = 0; c < 3; ++c) {
      const float v = p[c] + (1.0f - p[3]) * background[c];
      out[i * 3 + c] = static_cast<unsigned char>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
    }
  }
  return out;
}

double rms_difference_pct(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
  require(a.size() == b.size() && !a.empty(), "rms_difference_pct: images differ in size or are empty");
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = double(a[i]) - double(b[i]);
    s += d * d;
  }
  return 100.0 * std::sqrt(s / a.size()) / 255.0;
}

void write_png(const std::string& path, const std::vector<unsigned char>& rgb, int width, int height) {
  require(width > 0 && height > 0 && rgb.size() == static_cast<std::size_t>(width) * height * 3,
          "write_png: buffer size does not match " + std::to_string(width) + "x" + std::to_string(height));
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) io_fail("cannot create", tmp);
  std::string err;
  const bool ok = encode(f, nullptr, rgb, width, height, err);
  // fflush + fsync before rename: a crash must leave either the old file or the complete new one.
  const bool flushed = ok && std::fflush(f) == 0 && ::fsync(fileno(f)) == 0;
  const int saved = errno;
  std::fclose(f);
  if (!flushed) {
    std::remove(tmp.c_str());
    errno = saved;
    if (!ok) throw Error(ErrorCode::io_error, "cannot encode PNG '" + path + "': " + err);
    io_fail("cannot write", path);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    std::remove(tmp.c_str());
    errno = e;
    io_fail("cannot rename into place", path);
  }
}

std::vector<unsigned char> encode_png(const std::vector<unsigned char>& rgb, int width, int height) {
  require(width > 0 && height > 0 && rgb.size() == static_cast<std::size_t>(width) * height * 3,
          "encode_png: buffer size does not match " + std::to_string(width) + "x" + std::to_string(height));
  std::vector<unsigned char> png;
  std::string err;
  if (!encode(nullptr, &png, rgb, width, height, err)) throw Error(ErrorCode::io_error, "cannot encode PNG: " + err);
  return png;
}

std::vector<unsigned char> read_png_rgb(const std::string& path, int& width, int& height) {
  png_image img;
  std::memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path.c_str()))
    throw Error(ErrorCode::io_error, "cannot read PNG '" + path + "': " + img.message);
  img.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> out(PNG_IMAGE_SIZE(img));
  if (!png_image_finish_read(&img, nullptr, out.data(), 0, nullptr)) {
    png_image_free(&img);
    throw Error(ErrorCode::io_error, "cannot decode PNG '" + path + "': " + img.message);
  }
  width = static_cast<int>(img.width);
  height = static_cast<int>(img.height);
  return out;
}

}  // namespace penumbra::render
