#include "pipelines/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStandardAttributes.h>
#include <openexr.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "pipelines/exr_zip.h"
#include "pipelines/half_floats.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {

namespace {

std::array<float, 16> FromImath(const Imath::M44f& m) {
  std::array<float, 16> a;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) a[size_t(4 * i + j)] = m[i][j];
  return a;
}

// A whole frame rate up to 60 (a timeCode's frame field), or 0.
int WholeFps(double fps) { return fps >= 1 && fps <= 60 && fps == std::floor(fps) ? int(fps) : 0; }

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

namespace {

// The file through stdio (OpenEXR Core writes the header, the chunk table and our chunks
// through it). A failed write is remembered with its errno, and Core's messages are kept
// instead of printed, so that the exception can say what went wrong.
struct CoreSink {
  std::FILE* file = nullptr;
  int write_errno = 0;
  std::string message;
};

int64_t WriteAt(exr_const_context_t, void* user, const void* buffer, uint64_t size, uint64_t offset,
                exr_stream_error_func_ptr_t) {
  CoreSink& sink = *static_cast<CoreSink*>(user);
  if ((uint64_t(ftello(sink.file)) != offset && fseeko(sink.file, off_t(offset), SEEK_SET) != 0) ||
      std::fwrite(buffer, 1, size, sink.file) != size) {
    sink.write_errno = errno;
    return -1;
  }
  return int64_t(size);
}

void KeepMessage(exr_const_context_t context, exr_result_t, const char* message) {
  void* user = nullptr;
  if (exr_get_user_data(context, &user) == EXR_ERR_SUCCESS && user) static_cast<CoreSink*>(user)->message = message;
}

void Check(exr_result_t result, const CoreSink& sink, const std::string& path) {
  if (result == EXR_ERR_SUCCESS) return;
  const std::string reason = sink.write_errno ? std::strerror(sink.write_errno)
                             : sink.message.empty() ? exr_get_default_error_message(result) : sink.message;
  throw std::runtime_error(path + ": " + reason);
}

void AddMetadata(const ExrMetadata& m, exr_context_t context, const CoreSink& sink, const std::string& path) {
  auto matrix = [&](const char* name, const std::optional<std::array<float, 16>>& value) {
    if (!value) return;
    exr_attr_m44f_t a;
    std::copy(value->begin(), value->end(), a.m);  // row-major, as Imath's M44f
    Check(exr_attr_set_m44f(context, 0, name, &a), sink, path);
  };
  matrix("worldToCamera", m.world_to_camera);
  matrix("worldToNDC", m.world_to_ndc);
  if (m.frames_per_second > 0) {
    const Imf::Rational r(m.frames_per_second);  // OpenEXR's nearest fraction
    const exr_attr_rational_t a = {r.n, r.d};
    Check(exr_attr_set_rational(context, 0, "framesPerSecond", &a), sink, path);
  }
  const int fps = WholeFps(m.frames_per_second);
  if (fps > 0 && m.frame >= 0) {
    const long seconds = m.frame / fps;
    if (seconds < 24 * 3600) {  // a day: the hours field's range
      const Imf::TimeCode code(int(seconds / 3600), int(seconds / 60 % 60), int(seconds % 60), int(m.frame % fps));
      const exr_attr_timecode_t a = {code.timeAndFlags(), code.userData()};
      Check(exr_attr_set_timecode(context, 0, "timeCode", &a), sink, path);
    }
  }
}

// Rows [y, y + rows) of every channel as the file stores them: line after line, in each line
// the channels in the order of `sorted` (by name), half channels converted, little-endian as
// EXR is (x86 is).
void PackRows(const std::vector<const ExrChannel*>& sorted, int width, int y, int rows, std::uint16_t* out) {
  for (int row = y; row < y + rows; ++row)
    for (const ExrChannel* c : sorted) {
      const float* in = c->data.data() + size_t(row) * size_t(width);
      if (c->half) {
        FloatsToHalves(in, size_t(width), out);
        out += width;
      } else {
        std::memcpy(out, in, sizeof(float) * size_t(width));
        out += 2 * width;
      }
    }
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
  std::vector<const ExrChannel*> sorted;  // a file's channels are sorted by name
  for (const ExrChannel& c : channels) sorted.push_back(&c);
  std::sort(sorted.begin(), sorted.end(), [](const ExrChannel* a, const ExrChannel* b) { return a->name < b->name; });
  for (size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i]->name == sorted[i - 1]->name)
      throw std::invalid_argument(path + ": two channels named '" + sorted[i]->name + "'");
  size_t line_halves = 0;  // a line's size in 16-bit units
  for (const ExrChannel* c : sorted) line_halves += size_t(width) * (c->half ? 1 : 2);
  thread_local ZipChunkCache cache;

  formats::WriteFileAtomically(path, [&](const std::string& tmp) {
    // through stdio, whose every failure (the close's included) is reported with its errno
    formats::WriteWithStdio(tmp, [&](std::FILE* f) {
      CoreSink sink;
      sink.file = f;
      exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
      init.user_data = &sink;
      init.write_fn = WriteAt;
      init.error_handler_fn = KeepMessage;
      exr_context_t context = nullptr;
      Check(exr_start_write(&context, tmp.c_str(), EXR_WRITE_FILE_DIRECTLY, &init), sink, tmp);
      struct Finish {  // frees the context when a step throws (exr_finish also nulls it)
        exr_context_t* context;
        ~Finish() {
          if (*context) exr_finish(context);
        }
      } finish{&context};
      const bool long_names =  // over 31 characters: a flag in the file's version field
          std::any_of(sorted.begin(), sorted.end(), [](const ExrChannel* c) { return c->name.size() > 31; });
      if (long_names) Check(exr_set_longname_support(context, 1), sink, tmp);
      int part = 0;
      Check(exr_add_part(context, "", EXR_STORAGE_SCANLINE, &part), sink, tmp);
      const bool zip = compression == ExrCompression::kZip;
      Check(exr_initialize_required_attr_simple(context, part, width, height,
                                                zip ? EXR_COMPRESSION_ZIP : EXR_COMPRESSION_NONE),
            sink, tmp);
      for (const ExrChannel* c : sorted)
        Check(exr_add_channel(context, part, c->name.c_str(), c->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                              EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
              sink, tmp);
      AddMetadata(metadata, context, sink, tmp);
      Check(exr_write_header(context), sink, tmp);
      int32_t lines = 1;  // per chunk: 16 for ZIP, 1 uncompressed
      Check(exr_get_scanlines_per_chunk(context, part, &lines), sink, tmp);
      std::vector<std::uint16_t> raw(line_halves * size_t(lines));
      for (int y = 0; y < height; y += lines) {
        const int rows = std::min(lines, height - y);
        PackRows(sorted, width, y, rows, raw.data());
        const auto* bytes = reinterpret_cast<const unsigned char*>(raw.data());
        const size_t n = 2 * line_halves * size_t(rows);
        if (!zip) {
          Check(exr_write_scanline_chunk(context, part, y, bytes, n), sink, tmp);
          continue;
        }
        const std::vector<unsigned char>& packed = cache.Encoded(size_t(y / lines), bytes, n, 2 * line_halves);
        Check(exr_write_scanline_chunk(context, part, y, packed.data(), packed.size()), sink, tmp);
      }
      Check(exr_finish(&context), sink, tmp);  // writes the chunk table
      return sink.write_errno == 0;
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
