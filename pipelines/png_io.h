// PNG images of 8-bit pixels, written with libpng. No VTK here, so BackgroundWriter jobs can
// encode PNGs on worker threads (VTK objects must stay on the thread that made them: its
// garbage collector is not thread-safe).
//
// Pixel layout: row-major, `channels` bytes per pixel (3: RGB, 4: RGBA), row 0 at the TOP of
// the image (the PNG convention; VTK images start at the bottom and are flipped by callers).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace wobble::pipelines {

struct PngPixels {
  int width = 0, height = 0;
  int channels = 3;             // 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA
  std::vector<uint8_t> bytes;   // width * height * channels, row 0 at the top
};

// Writes `image` as a PNG atomically (temporary file + rename). compression: zlib level 0
// (none, fastest) to 9 (smallest); PNG is lossless at every level. Throws
// std::invalid_argument for a bad size or pixel count, std::runtime_error (naming the path
// and reason) when the file cannot be written; an earlier file is then left intact.
void WritePngPixels(const std::string& path, const PngPixels& image, int compression = 5);

}  // namespace wobble::pipelines
