// pipelines/video_writer.h without VTK or a display (so the sanitizer build runs it too):
// synthetic frames, a dark square moving one column per frame, encoded and read back by
// FFmpeg's own programs (ffprobe for the stream, ffmpeg's decoder for the pixels), which
// wobble does not contain; and the failures: an unfinished writer, a full disk, bad sizes.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pipelines/video_writer.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 33, kHeight = 21, kSquare = 6;  // odd: the video is 34 x 22

// Frame k: white, with a black kSquare x kSquare square whose left column is 2 + k
PngPixels MovingSquare(int k) {
  PngPixels p;
  p.width = kWidth;
  p.height = kHeight;
  p.bytes.assign(size_t(kWidth) * kHeight * 3, 255);
  for (int y = 7; y < 7 + kSquare; ++y)
    for (int x = 2 + k; x < 2 + k + kSquare; ++x)
      for (int c = 0; c < 3; ++c) p.bytes[(size_t(y) * kWidth + x) * 3 + c] = 0;
  return p;
}

std::string Output(const std::string& command) {
  std::string text;
  if (FILE* pipe = popen(command.c_str(), "r")) {
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) text.append(buffer, n);
    pclose(pipe);
  }
  return text;
}

std::string ReadAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

class Video : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("wobble_video_test_" + std::to_string(::getpid()))).string();
    fs::create_directories(dir_);
    ASSERT_FALSE(Output("command -v ffprobe").empty()) << "ffprobe is missing: `make deps` installs Debian's ffmpeg";
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string WriteFrames(const std::string& name, int frames, double fps, VideoFormat format = VideoFormat::kMp4) {
    const std::string path = dir_ + "/" + name;
    VideoOptions options;
    options.format = format;
    options.fps = fps;
    VideoWriter video(path, kWidth, kHeight, options);
    for (int k = 0; k < frames; ++k) video.AddFrame(MovingSquare(k));
    EXPECT_EQ(video.Finish(), frames);
    return path;
  }
  std::string dir_;
};

TEST_F(Video, FfprobeReadsTheStreamAsWritten) {
  const std::string path = WriteFrames("square.mp4", 12, 24.0);
  const std::string probe = Output("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                   "stream=codec_name,pix_fmt,width,height,nb_read_frames,r_frame_rate,duration "
                                   "-of default=noprint_wrappers=1 '" + path + "'");
  EXPECT_NE(probe.find("codec_name=h264"), std::string::npos) << probe;
  EXPECT_NE(probe.find("pix_fmt=yuv420p"), std::string::npos) << probe;
  EXPECT_NE(probe.find("width=34\nheight=22"), std::string::npos) << probe;  // padded to even
  EXPECT_NE(probe.find("r_frame_rate=24/1"), std::string::npos) << probe;
  EXPECT_NE(probe.find("nb_read_frames=12"), std::string::npos) << probe;
  EXPECT_NE(probe.find("duration=0.500000"), std::string::npos) << probe;  // 12 frames / 24 fps
}

TEST_F(Video, FfmpegDecodesEachFrameWithItsSquareInPlace) {
  const int frames = 10;
  const std::string path = WriteFrames("square.mp4", frames, 30.0);
  const std::string raw = Output("ffmpeg -v error -i '" + path + "' -vf format=rgb24 -f rawvideo -");
  const size_t frame_bytes = size_t(kWidth + 1) * (kHeight + 1) * 3;
  ASSERT_EQ(raw.size(), frame_bytes * frames);
  for (int k = 0; k < frames; ++k) {
    // the square's left edge: the column where the square's middle row turns dark (< 128)
    const size_t row = size_t(7 + kSquare / 2) * (kWidth + 1) * 3;
    int left = -1;
    for (int x = 0; x < kWidth + 1 && left < 0; ++x)
      if (uint8_t(raw[k * frame_bytes + row + size_t(x) * 3 + 1]) < 128) left = x;
    EXPECT_EQ(left, 2 + k) << "frame " << k;
  }
  // the padded column and row repeat the last ones (white here), not black
  const size_t corner = frame_bytes - 3;
  EXPECT_GT(uint8_t(raw[corner + 1]), 200);
}

// The animated WebP, read by Pillow (Python's imaging library, its own libwebp binding):
// frames, size (odd, kept), loop, each frame's time in milliseconds, the square in place
TEST_F(Video, PillowReadsTheAnimatedWebp) {
  const std::string path = WriteFrames("square.webp", 8, 20.0, VideoFormat::kWebp);
  const std::string read = Output(
      "/usr/bin/python3 -c \"import sys; from PIL import Image\n"
      "im = Image.open(sys.argv[1]); print(im.format, im.size[0], im.size[1], im.n_frames, im.info.get('loop'))\n"
      "for k in range(im.n_frames):\n"
      "  im.seek(k); im.load(); row = im.convert('L').load()\n"
      "  print(im.info['timestamp'], next(x for x in range(im.size[0]) if row[x, 10] < 128))\" '" + path + "' 2>&1");
  std::istringstream lines(read);
  std::string format;
  int width = 0, height = 0, frames = 0, loop = -1;
  lines >> format >> width >> height >> frames >> loop;
  ASSERT_EQ(format, "WEBP") << read;
  EXPECT_EQ(width, kWidth);
  EXPECT_EQ(height, kHeight);
  EXPECT_EQ(frames, 8);
  EXPECT_EQ(loop, 0);  // forever
  for (int k = 0; k < frames; ++k) {
    int milliseconds = -1, left = -1;
    lines >> milliseconds >> left;
    EXPECT_EQ(milliseconds, 50 * k) << read;  // 20 fps
    EXPECT_EQ(left, 2 + k) << "frame " << k;
  }
}

TEST_F(Video, AnUnfinishedWriterLeavesTheEarlierFileAndNoTemporary) {
  const std::string path = WriteFrames("kept.mp4", 4, 30.0);
  const std::string before = ReadAll(path);
  {
    VideoWriter video(path, kWidth, kHeight);
    for (int k = 0; k < 3; ++k) video.AddFrame(MovingSquare(k));
  }  // destroyed unfinished: an exception in the render, say
  EXPECT_EQ(ReadAll(path), before);
  EXPECT_FALSE(fs::exists(formats::TempPathFor(path)));
}

TEST_F(Video, AFullDiskIsNamedAndKeepsTheEarlierFile) {
  const std::string path = WriteFrames("full.mp4", 4, 30.0);
  const std::string before = ReadAll(path);
  fs::create_symlink("/dev/full", formats::TempPathFor(path));  // every write: no space left
  VideoWriter video(path, kWidth, kHeight);
  try {
    for (int k = 0; k < 30; ++k) video.AddFrame(MovingSquare(k % 20));
    video.Finish();
    ADD_FAILURE() << "writing to a full disk should have failed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::strerror(ENOSPC)), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadAll(path), before);
  EXPECT_FALSE(fs::exists(fs::symlink_status(formats::TempPathFor(path))));
}

TEST_F(Video, BadSizesAndRatesAreRefused) {
  EXPECT_THROW(VideoWriter(dir_ + "/a.mp4", 0, 10), std::invalid_argument);
  VideoOptions zero_fps;
  zero_fps.fps = 0.0;
  EXPECT_THROW(VideoWriter(dir_ + "/a.mp4", 10, 10, zero_fps), std::invalid_argument);
  VideoWriter video(dir_ + "/a.mp4", kWidth, kHeight);
  PngPixels small = MovingSquare(0);
  small.width = 8;
  EXPECT_THROW(video.AddFrame(small), std::invalid_argument);
}

}  // namespace
}  // namespace wobble::pipelines
