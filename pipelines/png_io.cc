#include "pipelines/png_io.h"

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <png.h>
#include <stdexcept>

#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

// libpng reports errors by longjmp; this C-style function holds no C++ object whose
// destructor a jump could skip, and returns libpng's message (empty on success).
void PngError(png_structp png, png_const_charp message) {
  std::snprintf(static_cast<char*>(png_get_error_ptr(png)), 256, "%s", message);
  png_longjmp(png, 1);
}

void PngWarning(png_structp, png_const_charp) {}  // warnings do not stop a write

bool EncodePng(std::FILE* file, const PngPixels& image, int compression, png_bytep* rows, char* message) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, PngError, PngWarning);
  if (!png) {
    std::snprintf(message, 256, "out of memory");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  static const int kColour[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                 PNG_COLOR_TYPE_RGB_ALPHA};
  png_init_io(png, file);
  png_set_compression_level(png, compression);
  // rendered frames are mostly flat areas: at the fast levels the Up filter alone compresses
  // them within 2% of libpng's adaptive choice (a 640x480 demo frame at level 1: 15.4 kB
  // against 15.1 kB for None|Up and 15.0 kB for all five) and skips the per-row choice, the
  // larger part of the time (BM_EncodePng640x480 in bench/pipelines_bench.cc)
  if (compression <= 3) png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_UP);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, kColour[image.channels],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

void WritePngPixels(const std::string& path, const PngPixels& image, int compression) {
  if (image.width <= 0 || image.height <= 0) throw std::invalid_argument("PNG size must be positive: " + path);
  if (image.channels < 1 || image.channels > 4) throw std::invalid_argument("PNG needs 1 to 4 channels: " + path);
  const size_t stride = size_t(image.width) * size_t(image.channels);
  if (image.bytes.size() != stride * size_t(image.height))
    throw std::invalid_argument("PNG pixel count does not match its size: " + path);
  std::vector<png_bytep> rows(size_t(image.height));
  for (size_t y = 0; y < rows.size(); ++y) rows[y] = const_cast<png_bytep>(image.bytes.data() + y * stride);
  formats::WriteFileAtomically(path, [&](const std::string& tmp) {
    char message[256] = "";
    try {
      formats::WriteWithStdio(tmp, [&](std::FILE* file) {
        return EncodePng(file, image, std::clamp(compression, 0, 9), rows.data(), message);
      });
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(std::string(e.what()) + (message[0] ? std::string(" (PNG encoder: ") + message + ")" : ""));
    }
  });
}

}  // namespace wobble::pipelines
