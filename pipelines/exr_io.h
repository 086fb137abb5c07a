// OpenEXR images of named float channels: render frames (R, G, B, A, depth.Z), data images
// (disp.X, disp.Y) and any analysis field (cond, ...). No VTK here, only OpenEXR.
//
// Pixel layout everywhere: row-major, width × height floats per channel, row 0 at the TOP of
// the image (the EXR convention; VTK images start at the bottom and are flipped by callers).
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace wobble::pipelines {

struct ExrChannel {
  std::string name;         // e.g. "R", "depth.Z", "disp.X", "cond"
  std::vector<float> data;  // width * height values, row 0 at the top
  bool half = false;        // stored as 16-bit half floats (colour); read back as float
};

// The compressions of OpenEXR that wobble writes with (zlib at level 1 where zlib is used).
// kZip (16 lines a block) is the default of rendered frames: lossless, small (1.4% of the
// channels' bytes on the demo's frames) and the fastest of those that shrink them (ZIPS is as
// fast and larger, PIZ slower and larger). kDwaa is lossy on colour channels (R, G, B and layers' .R/.G/.B); OpenEXR keeps
// the others (alpha, depth, motion) exact. kNone for float data zlib cannot shrink (the
// displacement images).
enum class ExrCompression { kNone, kZip, kZips, kPiz, kDwaa };

// "none", "zip", "zips", "piz", "dwaa": the names of options (--exr-compression).
const char* ExrCompressionName(ExrCompression compression);
// Throws std::invalid_argument naming the value and the names accepted.
ExrCompression ExrCompressionFromName(const std::string& name);

// OpenEXR's standard attributes of a rendered frame (ImfStandardAttributes.h), for compositors:
// the camera (worldToCamera: left-handed, +z the viewing direction; worldToNDC: (0, 0) the top
// left and (1, 1) the bottom right of the image), and the frame's place in time
// (framesPerSecond; timeCode hh:mm:ss:ff from the frame number, when fps is whole and at most 60).
// Matrices are row-major in OpenEXR's row-vector convention: p' = p M.
struct ExrMetadata {
  std::optional<std::array<float, 16>> world_to_camera, world_to_ndc;
  double frames_per_second = 0;  // 0: not written
  long frame = -1;               // < 0: no timeCode
};

// Writes a scan-line EXR of the channels (32-bit floats, or halves) with OpenEXR's writer,
// atomically (temporary file + rename).
// Throws std::invalid_argument for a bad size, channel length or two channels of one name,
// std::runtime_error (naming the path and reason) when the file cannot be written; an earlier
// file is then left intact.
void WriteExrChannels(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels,
                      ExrCompression compression = ExrCompression::kZip, const ExrMetadata& metadata = {});

struct ExrImage {
  int width = 0, height = 0;
  std::map<std::string, std::vector<float>> channels;  // row 0 at the top
  ExrMetadata metadata;  // what of it the file has (frame: the timeCode's frame count at fps)
  // Value of channel `name` at pixel (x, y), y from the top. Throws std::out_of_range.
  float At(const std::string& name, int x, int y) const { return channels.at(name).at(size_t(y) * width + x); }
};

// Reads every channel of an EXR as floats. Throws std::runtime_error naming the file.
ExrImage ReadExrChannels(const std::string& path);

}  // namespace wobble::pipelines
