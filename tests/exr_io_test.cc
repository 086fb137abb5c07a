// The EXR writer (pipelines/exr_io.h) checked with OpenEXR's own reader, not wobble's: every
// compression's file holds the channels written, of the types asked for (half or float), the
// lossless ones bit for bit (halves rounded as Imath rounds them), DWAA exact everywhere but
// on colour; the header carries the compression and the camera and time attributes.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStandardAttributes.h>
#include <Imath/half.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include "pipelines/exr_io.h"
#include "support/pipelines_test_util.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;

// 37 x 53: three full 16-line blocks and a last one of 5 lines. Background (zero colour and
// alpha, infinite depth) around a patch of smooth values, a channel of random bits that
// zlib cannot shrink, and in the first line the values where rounding to half is delicate.
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
  // ties to even, half denormals, overflow to infinity, signed zero, infinities
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> edges = {-0.0f, 1.0f + 1.0f / 2048, 1.0f + 3.0f / 2048, 65504.0f, 65519.99f, 65520.0f,
                                    1e9f, -1e9f, inf, -inf, 5.96e-8f, 2.98e-8f, 2.99e-8f, 6.1e-5f, 1e-30f};
  std::copy(edges.begin(), edges.end(), ch[0].data.begin());
  return ch;
}

// What the file should hold: floats exactly, half channels rounded as Imath rounds them.
std::vector<float> Stored(const ExrChannel& c) {
  if (!c.half) return c.data;
  std::vector<float> out;
  for (float v : c.data) out.push_back(float(Imath::half(v)));
  return out;
}

// A file as OpenEXR's reader sees it: per channel its type, and its values as floats.
struct OpenExrView {
  Imf::Compression compression;
  int width = 0, height = 0;
  std::map<std::string, Imf::PixelType> types;
  std::map<std::string, std::vector<float>> values;
};

OpenExrView ReadWithOpenExr(const std::string& path) {
  Imf::InputFile file(path.c_str());
  const Imath::Box2i dw = file.header().dataWindow();
  OpenExrView v;
  v.compression = file.header().compression();
  v.width = dw.max.x - dw.min.x + 1;
  v.height = dw.max.y - dw.min.y + 1;
  Imf::FrameBuffer fb;
  for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
    v.types[it.name()] = it.channel().type;
    std::vector<float>& data = v.values[it.name()];
    data.resize(size_t(v.width) * size_t(v.height));
    fb.insert(it.name(), Imf::Slice(Imf::FLOAT, (char*)data.data(), sizeof(float), sizeof(float) * size_t(v.width)));
  }
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  return v;
}

void ExpectBitsEqual(const std::vector<float>& a, const std::vector<float>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(float) * a.size()), 0) << what;
}

TEST(ExrIo, LosslessCompressionsReadBackBitForBitWithOpenExrsReader) {
  const std::string dir = testing::TempDir("exr_lossless");
  const int w = 37, h = 53;
  const std::vector<ExrChannel> picture = Picture(w, h, 1);
  const std::pair<ExrCompression, Imf::Compression> cases[] = {{ExrCompression::kZip, Imf::ZIP_COMPRESSION},
                                                               {ExrCompression::kZips, Imf::ZIPS_COMPRESSION},
                                                               {ExrCompression::kPiz, Imf::PIZ_COMPRESSION},
                                                               {ExrCompression::kNone, Imf::NO_COMPRESSION}};
  for (const auto& [compression, imf] : cases) {
    SCOPED_TRACE(ExrCompressionName(compression));
    WriteExrChannels(dir + "/c.exr", w, h, picture, compression);
    const OpenExrView file = ReadWithOpenExr(dir + "/c.exr");
    EXPECT_EQ(file.compression, imf);
    ASSERT_EQ(file.width, w);
    ASSERT_EQ(file.height, h);
    ASSERT_EQ(file.values.size(), picture.size());
    for (const ExrChannel& c : picture) {
      ASSERT_TRUE(file.values.count(c.name)) << c.name;
      EXPECT_EQ(file.types.at(c.name), c.half ? Imf::HALF : Imf::FLOAT) << c.name;
      ExpectBitsEqual(file.values.at(c.name), Stored(c), c.name);
    }
    // wobble's reader agrees
    const ExrImage back = ReadExrChannels(dir + "/c.exr");
    for (const ExrChannel& c : picture) ExpectBitsEqual(back.channels.at(c.name), Stored(c), c.name);
  }
  fs::remove_all(dir);
}

// DWAA quantises colour (R, G, B, of any layer) in its DCT; OpenEXR keeps alpha, depth and
// the motion vectors exact, which is why it is offered at all for compositing frames.
TEST(ExrIo, DwaaIsLossyOnColourAloneAndKeepsTheOtherChannelsExact) {
  const std::string dir = testing::TempDir("exr_dwaa");
  const int w = 64, h = 48;
  std::vector<ExrChannel> ch = {{"R", {}, true},        {"G", {}, true},         {"B", {}, true},
                                {"A", {}, true},        {"depth.Z", {}, false},  {"forward.u", {}, true},
                                {"terrain.R", {}, true}};
  std::mt19937 random(5);
  std::uniform_real_distribution<float> noise(-0.02f, 0.02f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float s = float(x) / w, t = float(y) / h;  // smooth colour with a little grain
      ch[0].data.push_back(0.8f * s + noise(random) + 0.05f);
      ch[1].data.push_back(0.5f * t + noise(random) + 0.05f);
      ch[2].data.push_back(0.3f * s * t + noise(random) + 0.05f);
      ch[3].data.push_back(x > 10 && x < 50 ? 1.0f : 0.0f);
      ch[4].data.push_back(100.0f + 0.37f * float(x) - 0.11f * float(y) + noise(random));
      ch[5].data.push_back(3.0f * s - 1.0f + noise(random));
      ch[6].data.push_back(0.4f * t + noise(random) + 0.05f);
    }
  WriteExrChannels(dir + "/d.exr", w, h, ch, ExrCompression::kDwaa);
  const OpenExrView file = ReadWithOpenExr(dir + "/d.exr");
  EXPECT_EQ(file.compression, Imf::DWAA_COMPRESSION);
  ASSERT_EQ(file.values.size(), ch.size());
  bool colour_changed = false;
  for (const ExrChannel& c : ch) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(file.types.at(c.name), c.half ? Imf::HALF : Imf::FLOAT);
    const std::vector<float> stored = Stored(c);
    const std::vector<float>& got = file.values.at(c.name);
    const bool colour = c.name == "R" || c.name == "G" || c.name == "B" || c.name == "terrain.R";
    if (!colour) {
      ExpectBitsEqual(got, stored, c.name);
      continue;
    }
    double worst = 0;
    for (size_t i = 0; i < got.size(); ++i) worst = std::max(worst, double(std::abs(got[i] - stored[i])));
    EXPECT_LT(worst, 0.03);  // values up to 0.87: close (0.017 at most here), not equal
    colour_changed = colour_changed || worst > 0;
  }
  EXPECT_TRUE(colour_changed) << "DWAA left every colour value as it was: is it compressing at all?";
  fs::remove_all(dir);
}

// The standard attributes as OpenEXR's own accessors read them.
TEST(ExrIo, CameraAndTimeAttributesAsOpenExrReadsThem) {
  const std::string dir = testing::TempDir("exr_attributes");
  ExrMetadata m;
  m.world_to_camera = std::array<float, 16>{1, 0, 0, 0, 0, -1, 0, 0, 0, 0, -1, 0, 5, 6, 7, 1};
  m.world_to_ndc = std::array<float, 16>{0.5f, 0, 0, 0, 0, -0.25f, 0, 0, 0, 0, 1, 0, 0.5f, 0.5f, 0, 1};
  m.frames_per_second = 30;
  m.frame = 3725;  // 2 min 4 s and 5 frames
  WriteExrChannels(dir + "/m.exr", 2, 2, {{"depth.Z", {1, 2, 3, 4}}}, ExrCompression::kZip, m);
  Imf::InputFile file((dir + "/m.exr").c_str());
  const Imf::Header& header = file.header();
  ASSERT_TRUE(Imf::hasWorldToCamera(header) && Imf::hasWorldToNDC(header));
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(Imf::worldToCamera(header)[i][j], (*m.world_to_camera)[size_t(4 * i + j)]) << i << j;
      EXPECT_EQ(Imf::worldToNDC(header)[i][j], (*m.world_to_ndc)[size_t(4 * i + j)]) << i << j;
    }
  ASSERT_TRUE(Imf::hasFramesPerSecond(header) && Imf::hasTimeCode(header));
  EXPECT_EQ(Imf::framesPerSecond(header).n, 30);
  EXPECT_EQ(Imf::framesPerSecond(header).d, 1u);
  const Imf::TimeCode& tc = Imf::timeCode(header);
  EXPECT_EQ(tc.hours(), 0);
  EXPECT_EQ(tc.minutes(), 2);
  EXPECT_EQ(tc.seconds(), 4);
  EXPECT_EQ(tc.frame(), 5);
  // wobble's reader gives the frame back
  EXPECT_EQ(ReadExrChannels(dir + "/m.exr").metadata.frame, 3725);
  fs::remove_all(dir);
}

TEST(ExrIo, LongChannelNamesAndOneNameTwice) {
  const std::string dir = testing::TempDir("exr_names");
  const std::string long_name = "a.layer.name.longer.than.thirty.one.characters.X";
  WriteExrChannels(dir + "/long.exr", 3, 2, {{long_name, {1, 2, 3, 4, 5, 6}}});
  EXPECT_EQ(ReadWithOpenExr(dir + "/long.exr").values.at(long_name), std::vector<float>({1, 2, 3, 4, 5, 6}));
  EXPECT_THROW(WriteExrChannels(dir + "/twice.exr", 1, 1, {{"R", {1}}, {"R", {2}}}), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir + "/twice.exr"));
  fs::remove_all(dir);
}

TEST(ExrIo, CompressionNames) {
  for (ExrCompression c : {ExrCompression::kZip, ExrCompression::kZips, ExrCompression::kPiz, ExrCompression::kDwaa,
                           ExrCompression::kNone})
    EXPECT_EQ(ExrCompressionFromName(ExrCompressionName(c)), c);
  try {
    ExrCompressionFromName("rle");
    ADD_FAILURE() << "rle is not offered";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'rle'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("zip, zips, piz, dwaa, none"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace wobble::pipelines
