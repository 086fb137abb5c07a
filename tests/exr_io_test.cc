// The EXR writer (pipelines/exr_io.h) against OpenEXR's own: wobble packs and deflates the
// ZIP chunks itself and reuses the compressed bytes of blocks it has seen, so the files must
// read back exactly as the same pixels written by OpenEXR's C++ writer, and a file whose
// chunks came from the cache must be byte for byte the file a fresh writer makes.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <Imath/half.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <thread>

#include "pipelines/exr_io.h"
#include "support/pipelines_test_util.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;

// 37 x 53: three full 16-line chunks and a last one of 5 lines. Background (zero colour and
// alpha, infinite depth) around a patch of smooth values, and a channel of random bits that
// zlib cannot shrink (its chunks are stored as they are).
std::vector<ExrChannel> Picture(int width, int height, unsigned seed) {
  std::vector<ExrChannel> ch = {{"R", {}, true}, {"A", {}, true}, {"depth.Z", {}, false}, {"noise", {}, false}};
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> uniform(-1e4f, 1e4f);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const bool inside = x > 5 && x < 30 && y > 18 && y < 33;
      ch[0].data.push_back(inside ? 0.01f * float(x * y) : 0.0f);
      ch[1].data.push_back(inside ? 1.0f : 0.0f);
      ch[2].data.push_back(inside ? 3.5f + 0.125f * float(x) : std::numeric_limits<float>::infinity());
      ch[3].data.push_back(y < 16 ? 0.0f : uniform(random));
    }
  return ch;
}

// What the file should hold: floats exactly, half channels rounded as OpenEXR rounds them.
std::vector<float> Stored(const ExrChannel& c) {
  if (!c.half) return c.data;
  std::vector<float> out;
  for (float v : c.data) out.push_back(float(Imath::half(v)));
  return out;
}

void WriteWithOpenExr(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels) {
  Imf::Header header(width, height);
  header.compression() = Imf::ZIP_COMPRESSION;
  Imf::FrameBuffer fb;
  std::vector<std::vector<Imath::half>> halves;
  halves.reserve(channels.size());
  for (const ExrChannel& c : channels) {
    if (c.half) {
      halves.emplace_back(c.data.begin(), c.data.end());
      header.channels().insert(c.name, Imf::Channel(Imf::HALF));
      fb.insert(c.name, Imf::Slice(Imf::HALF, (char*)halves.back().data(), sizeof(Imath::half),
                                   sizeof(Imath::half) * size_t(width)));
    } else {
      header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, (char*)c.data.data(), sizeof(float), sizeof(float) * size_t(width)));
    }
  }
  Imf::OutputFile file(path.c_str(), header);
  file.setFrameBuffer(fb);
  file.writePixels(height);
}

std::string Bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void ExpectBitsEqual(const std::vector<float>& a, const std::vector<float>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(float) * a.size()), 0) << what;
}

TEST(ExrZip, ReadsBackAsTheSamePixelsAsOpenExrsOwnWriter) {
  const std::string dir = testing::TempDir("exr_zip");
  const int w = 37, h = 53;
  const std::vector<ExrChannel> picture = Picture(w, h, 1);
  for (ExrCompression compression : {ExrCompression::kZip, ExrCompression::kNone}) {
    WriteExrChannels(dir + "/ours.exr", w, h, picture, compression);
    WriteWithOpenExr(dir + "/openexr.exr", w, h, picture);
    const ExrImage ours = ReadExrChannels(dir + "/ours.exr"), reference = ReadExrChannels(dir + "/openexr.exr");
    ASSERT_EQ(ours.width, w);
    ASSERT_EQ(ours.height, h);
    ASSERT_EQ(ours.channels.size(), picture.size());
    for (const ExrChannel& c : picture) {
      ExpectBitsEqual(ours.channels.at(c.name), reference.channels.at(c.name), c.name);
      ExpectBitsEqual(ours.channels.at(c.name), Stored(c), c.name);
    }
  }
  // zlib's level 1 against OpenEXR's default level: a little larger, never far off
  WriteExrChannels(dir + "/ours.exr", w, h, picture, ExrCompression::kZip);
  EXPECT_LT(fs::file_size(dir + "/ours.exr"), 1.2 * double(fs::file_size(dir + "/openexr.exr")));
  fs::remove_all(dir);
}

TEST(ExrZip, ReusedChunksAreTheBytesAFreshWriterMakes) {
  const std::string dir = testing::TempDir("exr_reuse");
  const int w = 37, h = 53;
  // the previous frame, then this one: one pixel changed in the second chunk, and the third
  // chunk made the same as the second (the block above)
  const std::vector<ExrChannel> previous = Picture(w, h, 2);
  std::vector<ExrChannel> now = previous;
  now[0].data[size_t(20) * w + 10] = 0.75f;
  for (ExrChannel& c : now) std::copy_n(c.data.begin() + 16 * w, 16 * w, c.data.begin() + 32 * w);
  WriteExrChannels(dir + "/previous.exr", w, h, previous, ExrCompression::kZip);
  WriteExrChannels(dir + "/now.exr", w, h, now, ExrCompression::kZip);
  WriteExrChannels(dir + "/again.exr", w, h, now, ExrCompression::kZip);  // every chunk reused
  // a new thread starts with no chunks to reuse
  std::thread fresh([&] { WriteExrChannels(dir + "/fresh.exr", w, h, now, ExrCompression::kZip); });
  fresh.join();
  const std::string expected = Bytes(dir + "/fresh.exr");
  EXPECT_EQ(Bytes(dir + "/now.exr"), expected);
  EXPECT_EQ(Bytes(dir + "/again.exr"), expected);
  const ExrImage back = ReadExrChannels(dir + "/now.exr");
  for (const ExrChannel& c : now) ExpectBitsEqual(back.channels.at(c.name), Stored(c), c.name);
  // and an image of another size after these: nothing of theirs leaks into it
  const std::vector<ExrChannel> small = Picture(w, 20, 3);
  WriteExrChannels(dir + "/small.exr", w, 20, small, ExrCompression::kZip);
  const ExrImage back_small = ReadExrChannels(dir + "/small.exr");
  for (const ExrChannel& c : small) ExpectBitsEqual(back_small.channels.at(c.name), Stored(c), c.name);
  fs::remove_all(dir);
}

TEST(ExrZip, LongChannelNamesAndOneNameTwice) {
  const std::string dir = testing::TempDir("exr_names");
  const std::string long_name = "a.layer.name.longer.than.thirty.one.characters.X";
  WriteExrChannels(dir + "/long.exr", 3, 2, {{long_name, {1, 2, 3, 4, 5, 6}}});
  EXPECT_EQ(ReadExrChannels(dir + "/long.exr").channels.at(long_name), std::vector<float>({1, 2, 3, 4, 5, 6}));
  EXPECT_THROW(WriteExrChannels(dir + "/twice.exr", 1, 1, {{"R", {1}}, {"R", {2}}}), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir + "/twice.exr"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace wobble::pipelines
