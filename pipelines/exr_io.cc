#include "pipelines/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "pipelines/half_floats.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {

namespace {
// Imf::OStream over a FILE*: a short write throws with the system's reason, and is
// remembered for writes OpenEXR makes in destructors (which cannot throw).
class StdioStream : public Imf::OStream {
 public:
  StdioStream(std::FILE* f, const std::string& name) : Imf::OStream(name.c_str()), f_(f) {}
  void write(const char c[], int n) override {
    if (n > 0 && std::fwrite(c, 1, size_t(n), f_) != size_t(n)) Fail();
  }
  uint64_t tellp() override { return uint64_t(ftello(f_)); }
  void seekp(uint64_t pos) override {
    if (fseeko(f_, off_t(pos), SEEK_SET) != 0) Fail();
  }
  bool failed() const { return failed_; }

 private:
  void Fail() {
    failed_ = true;
    throw std::runtime_error(std::string(fileName()) + ": " + std::strerror(errno));
  }
  std::FILE* f_;
  bool failed_ = false;
};
}  // namespace

namespace {

Imath::M44f ToImath(const std::array<float, 16>& m) {
  return Imath::M44f(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11], m[12], m[13], m[14], m[15]);
}
std::array<float, 16> FromImath(const Imath::M44f& m) {
  std::array<float, 16> a;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) a[size_t(4 * i + j)] = m[i][j];
  return a;
}

// A whole frame rate up to 60 (a timeCode's frame field), or 0.
int WholeFps(double fps) { return fps >= 1 && fps <= 60 && fps == std::floor(fps) ? int(fps) : 0; }

void AddMetadata(const ExrMetadata& m, Imf::Header* header) {
  if (m.world_to_camera) Imf::addWorldToCamera(*header, ToImath(*m.world_to_camera));
  if (m.world_to_ndc) Imf::addWorldToNDC(*header, ToImath(*m.world_to_ndc));
  if (m.frames_per_second > 0) Imf::addFramesPerSecond(*header, Imf::Rational(m.frames_per_second));
  const int fps = WholeFps(m.frames_per_second);
  if (fps > 0 && m.frame >= 0) {
    const long seconds = m.frame / fps;
    if (seconds < 24 * 3600)  // a day: the hours field's range
      Imf::addTimeCode(*header, Imf::TimeCode(int(seconds / 3600), int(seconds / 60 % 60), int(seconds % 60),
                                              int(m.frame % fps)));
  }
}

ExrMetadata ReadMetadata(const Imf::Header& header) {
  ExrMetadata m;
  if (Imf::hasWorldToCamera(header)) m.world_to_camera = FromImath(Imf::worldToCamera(header));
  if (Imf::hasWorldToNDC(header)) m.world_to_ndc = FromImath(Imf::worldToNDC(header));
  if (Imf::hasFramesPerSecond(header)) {
    const Imf::Rational r = Imf::framesPerSecond(header);
    m.frames_per_second = double(r);
  }
  const int fps = WholeFps(m.frames_per_second);
  if (Imf::hasTimeCode(header) && fps > 0) {
    const Imf::TimeCode& tc = Imf::timeCode(header);
    m.frame = ((long(tc.hours()) * 60 + tc.minutes()) * 60 + tc.seconds()) * fps + tc.frame();
  }
  return m;
}

}  // namespace

void WriteExrChannels(const std::string& path, int width, int height, const std::vector<ExrChannel>& channels,
                      ExrCompression compression, const ExrMetadata& metadata) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument(path + ": image size " + std::to_string(width) + "x" + std::to_string(height));
  if (channels.empty()) throw std::invalid_argument(path + ": no channels to write");
  for (const ExrChannel& c : channels)
    if (c.data.size() != size_t(width) * size_t(height))
      throw std::invalid_argument(path + ": channel '" + c.name + "' has " + std::to_string(c.data.size()) +
                                  " values, expected " + std::to_string(size_t(width) * height));
  formats::WriteFileAtomically(path, [&](const std::string& tmp) {
    Imf::Header header(width, height);
    AddMetadata(metadata, &header);
    switch (compression) {
      case ExrCompression::kNone: header.compression() = Imf::NO_COMPRESSION; break;
      case ExrCompression::kRle: header.compression() = Imf::RLE_COMPRESSION; break;
      case ExrCompression::kZip:
        header.compression() = Imf::ZIP_COMPRESSION;
        header.zipCompressionLevel() = 1;  // a few percent larger than the default, several times faster
        break;
      case ExrCompression::kPiz: header.compression() = Imf::PIZ_COMPRESSION; break;
    }
    Imf::FrameBuffer fb;
    // the half channels' bits, converted here (into uninitialised memory: a frame's worth of
    // zeroing cost as much as the conversion)
    std::vector<std::unique_ptr<std::uint16_t[]>> halves;
    halves.reserve(channels.size());
    for (const ExrChannel& c : channels) {
      if (c.half) {
        halves.emplace_back(new std::uint16_t[c.data.size()]);
        FloatsToHalves(c.data.data(), c.data.size(), halves.back().get());
        header.channels().insert(c.name, Imf::Channel(Imf::HALF));
        fb.insert(c.name, Imf::Slice(Imf::HALF, (char*)halves.back().get(), sizeof(std::uint16_t),
                                     sizeof(std::uint16_t) * size_t(width)));
        continue;
      }
      header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, (char*)c.data.data(), sizeof(float), sizeof(float) * size_t(width)));
    }
    // through stdio, whose every failure (the close's included) is reported with its errno:
    // OpenEXR's own std::ofstream lost a full disk's error and left an empty file
    formats::WriteWithStdio(tmp, [&](std::FILE* f) {
      StdioStream stream(f, tmp);
      {
        Imf::OutputFile file(stream, header);
        file.setFrameBuffer(fb);
        file.writePixels(height);
      }  // the destructor writes the line offsets
      return !stream.failed();
    });
  });
}

ExrImage ReadExrChannels(const std::string& path) {
  // before opening: opening a FIFO waits for a writer
  const std::string kind = formats::NonRegularKind(path);
  if (!kind.empty()) throw std::runtime_error(path + ": is " + kind + ", not a regular file");
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    ExrImage image;
    image.metadata = ReadMetadata(file.header());
    image.width = dw.max.x - dw.min.x + 1;
    image.height = dw.max.y - dw.min.y + 1;
    Imf::FrameBuffer fb;
    const size_t n = size_t(image.width) * size_t(image.height);
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it) {
      std::vector<float>& data = image.channels[it.name()];
      data.assign(n, 0.0f);
      // the slice base points at pixel (0, 0) of the data window's coordinates
      char* base = (char*)(data.data() - dw.min.x - size_t(dw.min.y) * image.width);
      fb.insert(it.name(), Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * size_t(image.width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return image;
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot read as OpenEXR: " + e.what());
  }
}

}  // namespace wobble::pipelines
