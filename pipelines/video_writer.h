// Video files of rendered frames, encoded by FFmpeg's libraries (libavcodec, libavformat,
// libswscale from Debian): an H.264 MP4 to play in a talk or a browser, or an animated WebP
// (libwebp through libavcodec) that a README shows like a GIF, in full colour. No VTK here:
// the frames arrive as pixels copied out of the render window (PixelsOf), and are converted
// and encoded on the writer's own thread while the caller renders the next frame.
//
// The MP4 as browsers and players want it:
//   - H.264 (libx264), High profile, yuv420p (4:2:0: what every hardware decoder plays);
//   - colour tagged BT.709, limited range, and converted with BT.709's coefficients, so players
//     show the colours of the PNG frames;
//   - even width and height (4:2:0 needs them): an odd frame gets one more column or row,
//     a copy of its last;
//   - `faststart`: the index (moov) before the data, so a browser starts playing before the
//     whole file arrived;
//   - frame k at time k / fps exactly (time base 1/fps as a rational), duration frames / fps.
// The animated WebP: lossy (VP8, libwebp's own RGB conversion), any size, looping forever,
// frame k shown from k / fps for 1 / fps (rounded to libwebp's milliseconds).
// The file is written atomically (formats/atomic_file.h): to FILE.tmp, renamed over FILE by
// Finish(); a writer destroyed unfinished, or one that failed, leaves FILE as it was.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "pipelines/png_io.h"

namespace wobble::pipelines {

enum class VideoFormat { kMp4, kWebp };

struct VideoOptions {
  VideoFormat format = VideoFormat::kMp4;
  double fps = 30.0;  // frames per second, > 0 (a rational close to it is the time base)
  // x264's constant rate factor: 0 lossless … 51 worst; 18 is visually lossless for these
  // flat-shaded pictures and keeps a 10 s 640x480 run well under a megabyte.
  int crf = 18;
  // x264's speed/size trade-off; "fast" keeps encoding off the render's critical path on two cores
  std::string preset = "veryfast";
  // WebP: libwebp's quality 0-100 (lossy); 75 keeps the thin lines and a 10 s 640x480 run small
  double webp_quality = 75.0;
};

class VideoWriter {
 public:
  // Starts the writer for frames of width x height pixels (RGB, 3 channels). Throws
  // std::invalid_argument for a bad size or fps; a file that cannot be opened is reported by
  // the first AddFrame or by Finish, as std::runtime_error naming `path`.
  VideoWriter(const std::string& path, int width, int height, const VideoOptions& options = {});
  ~VideoWriter();  // unfinished: stops the encoder and removes the temporary file
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // Queues the next frame (row 0 at the top, as PngPixels); blocks while a few frames wait
  // to be encoded. Rethrows the encoder's error if it failed.
  void AddFrame(PngPixels frame);
  // Encodes what is queued, writes the index and renames the file into place; returns the
  // number of frames in it. Throws std::runtime_error naming the file when anything failed.
  long Finish();

  const std::string& path() const { return path_; }
  VideoFormat format() const { return options_.format; }

 private:
  void Encode();  // the writer thread
  std::optional<PngPixels> NextFrame();  // empty: no more frames (finished or abandoned)

  const std::string path_;
  const int width_, height_;
  const VideoOptions options_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<PngPixels> queue_;
  bool closing_ = false, abandoned_ = false, done_ = false;
  long encoded_ = 0;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace wobble::pipelines
