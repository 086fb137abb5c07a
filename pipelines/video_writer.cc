#include "pipelines/video_writer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <utility>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

// Frames waiting to be encoded: enough to absorb a slow frame, few enough to bound the memory
constexpr size_t kMaxQueued = 4;

std::string AvError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(code, text, sizeof(text));
  return text;
}

void Check(int code, const char* what) {
  if (code < 0) throw std::runtime_error(std::string(what) + ": " + AvError(code));
}

struct FormatCloser {
  void operator()(AVFormatContext* f) const {
    if (f->pb) avio_closep(&f->pb);
    avformat_free_context(f);
  }
};
struct CodecCloser {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct FrameCloser {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct PacketCloser {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct ScalerCloser {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};

// The frame with its last column and row repeated up to even_width x even_height
void PadToEven(const PngPixels& in, int even_width, int even_height, std::vector<uint8_t>* out) {
  const size_t in_row = size_t(in.width) * 3, out_row = size_t(even_width) * 3;
  out->resize(out_row * size_t(even_height));
  for (int y = 0; y < even_height; ++y) {
    const uint8_t* src = in.bytes.data() + size_t(std::min(y, in.height - 1)) * in_row;
    uint8_t* dst = out->data() + size_t(y) * out_row;
    std::memcpy(dst, src, in_row);
    if (even_width > in.width) std::memcpy(dst + in_row, src + in_row - 3, 3);
  }
}

}  // namespace

VideoWriter::VideoWriter(const std::string& path, int width, int height, const VideoOptions& options)
    : path_(path), width_(width), height_(height), options_(options) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw std::invalid_argument(path + ": a video frame of " + std::to_string(width) + " x " + std::to_string(height) +
                                " pixels (1 to 16384 each)");
  if (!(options.fps > 0.0 && options.fps <= 1000.0))
    throw std::invalid_argument(path + ": video fps must be above 0 and at most 1000");
  thread_ = std::thread([this] { Encode(); });
}

VideoWriter::~VideoWriter() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    abandoned_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void VideoWriter::AddFrame(PngPixels frame) {
  if (frame.width != width_ || frame.height != height_ || frame.channels != 3 ||
      frame.bytes.size() != size_t(width_) * size_t(height_) * 3)
    throw std::invalid_argument(path_ + ": a video frame must be " + std::to_string(width_) + " x " +
                                std::to_string(height_) + " RGB pixels like the first");
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return queue_.size() < kMaxQueued || done_; });
  if (error_) std::rethrow_exception(error_);
  if (closing_) throw std::logic_error(path_ + ": a frame added after the video was finished");
  if (done_) return;  // outputs discarded (an MPI rank but the first: formats/atomic_file.h)
  queue_.push_back(std::move(frame));
  changed_.notify_all();
}

long VideoWriter::Finish() {
  if (!thread_.joinable()) throw std::logic_error(path_ + ": the video was already finished");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  changed_.notify_all();
  thread_.join();
  if (error_) std::rethrow_exception(error_);
  return encoded_;
}

std::optional<PngPixels> VideoWriter::NextFrame() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return !queue_.empty() || closing_ || abandoned_; });
  if (abandoned_ || queue_.empty()) return std::nullopt;
  PngPixels frame = std::move(queue_.front());
  queue_.pop_front();
  changed_.notify_all();
  return frame;
}

void VideoWriter::Encode() {
  try {
    formats::WriteFileAtomically(path_, [&](const std::string& temp_path) {
      // FFmpeg reports through its own log; wobble says what went wrong in its exceptions,
      // and x264's statistics are noise on the render's terminal
      av_log_set_level(AV_LOG_ERROR);
      const bool mp4 = options_.format == VideoFormat::kMp4;
      // 4:2:0 needs an even size; WebP takes any (libwebp converts the RGB itself)
      const int even_width = mp4 ? width_ + (width_ & 1) : width_, even_height = mp4 ? height_ + (height_ & 1) : height_;
      const AVPixelFormat pixels = mp4 ? AV_PIX_FMT_YUV420P : AV_PIX_FMT_RGB32;
      const AVRational rate = av_d2q(options_.fps, 1001000);  // 30 → 30/1, 29.97 → 30000/1001

      AVFormatContext* raw_format = nullptr;
      // the format is named: the temporary file's ".tmp" says nothing about it
      Check(avformat_alloc_output_context2(&raw_format, nullptr, mp4 ? "mp4" : "webp", temp_path.c_str()),
            "cannot start the file");
      std::unique_ptr<AVFormatContext, FormatCloser> format(raw_format);
      const char* codec_name = mp4 ? "libx264" : "libwebp_anim";
      const AVCodec* codec = avcodec_find_encoder_by_name(codec_name);
      if (!codec) throw std::runtime_error(std::string("FFmpeg's libavcodec has no ") + codec_name + " encoder (Debian's libavcodec59 has)");
      std::unique_ptr<AVCodecContext, CodecCloser> encoder(avcodec_alloc_context3(codec));
      if (!encoder) throw std::runtime_error("out of memory for the encoder");
      encoder->width = even_width;
      encoder->height = even_height;
      encoder->pix_fmt = pixels;
      encoder->time_base = av_inv_q(rate);  // frame k at pts k: time k / fps
      encoder->framerate = rate;
      // one thread: the render and the PNG writers already share the cores, and x264's frame
      // threads only queued behind them (frames + mp4 took 2x the frames' time, 1.1-1.6x with one)
      encoder->thread_count = 1;
      if (mp4) {
        encoder->gop_size = std::max(1, int(std::lround(2.0 * options_.fps)));  // a key frame every 2 s, for seeking
        encoder->color_range = AVCOL_RANGE_MPEG;
        encoder->colorspace = AVCOL_SPC_BT709;
        encoder->color_primaries = AVCOL_PRI_BT709;
        encoder->color_trc = AVCOL_TRC_BT709;
        Check(av_opt_set(encoder->priv_data, "preset", options_.preset.c_str(), 0), "x264 preset");
        Check(av_opt_set(encoder->priv_data, "crf", std::to_string(options_.crf).c_str(), 0), "x264 crf");
        Check(av_opt_set(encoder->priv_data, "profile", "high", 0), "x264 profile");
      } else {
        Check(av_opt_set_double(encoder->priv_data, "quality", options_.webp_quality, 0), "WebP quality");
      }
      if (format->oformat->flags & AVFMT_GLOBALHEADER) encoder->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
      Check(avcodec_open2(encoder.get(), codec, nullptr), "cannot open the encoder");

      AVStream* stream = avformat_new_stream(format.get(), nullptr);
      if (!stream) throw std::runtime_error("out of memory for the video stream");
      stream->time_base = encoder->time_base;
      stream->avg_frame_rate = rate;
      Check(avcodec_parameters_from_context(stream->codecpar, encoder.get()), "video stream parameters");
      Check(avio_open(&format->pb, temp_path.c_str(), AVIO_FLAG_WRITE), "cannot open the file");
      AVDictionary* muxer_options = nullptr;
      if (mp4) av_dict_set(&muxer_options, "movflags", "+faststart", 0);  // the index first: plays while loading
      else av_dict_set(&muxer_options, "loop", "0", 0);                   // a README's animation loops forever
      const int header = avformat_write_header(format.get(), &muxer_options);
      av_dict_free(&muxer_options);
      Check(header, "cannot write the file's header");

      // MP4: RGB (full range) to BT.709 limited-range 4:2:0, the colours the file is tagged with;
      // WebP: RGB to BGRA, libwebp's input
      std::unique_ptr<SwsContext, ScalerCloser> scaler(sws_getContext(
          even_width, even_height, AV_PIX_FMT_RGB24, even_width, even_height, pixels, SWS_BILINEAR, nullptr, nullptr, nullptr));
      if (!scaler) throw std::runtime_error("cannot convert the RGB frames");
      if (mp4)
        sws_setColorspaceDetails(scaler.get(), sws_getCoefficients(SWS_CS_DEFAULT), 1, sws_getCoefficients(SWS_CS_ITU709),
                                 0, 0, 1 << 16, 1 << 16);
      std::unique_ptr<AVFrame, FrameCloser> picture(av_frame_alloc());
      std::unique_ptr<AVPacket, PacketCloser> packet(av_packet_alloc());
      if (!picture || !packet) throw std::runtime_error("out of memory for a video frame");
      picture->format = pixels;
      picture->width = even_width;
      picture->height = even_height;
      if (mp4) {
        picture->color_range = AVCOL_RANGE_MPEG;
        picture->colorspace = AVCOL_SPC_BT709;
      }
      Check(av_frame_get_buffer(picture.get(), 0), "video frame buffer");

      auto write_packets = [&] {
        for (;;) {
          const int got = avcodec_receive_packet(encoder.get(), packet.get());
          if (got == AVERROR(EAGAIN) || got == AVERROR_EOF) return;
          Check(got, "encoding failed");
          // H.264: one frame per packet, the last one's duration makes the file's frames / fps
          // (libwebp_anim hands over the whole animation as one packet, its timing inside)
          if (mp4) packet->duration = 1;
          av_packet_rescale_ts(packet.get(), encoder->time_base, stream->time_base);
          packet->stream_index = stream->index;
          Check(av_interleaved_write_frame(format.get(), packet.get()), "cannot write to the file");
        }
      };
      std::vector<uint8_t> rgb;
      while (std::optional<PngPixels> frame = NextFrame()) {
        PadToEven(*frame, even_width, even_height, &rgb);
        Check(av_frame_make_writable(picture.get()), "video frame buffer");
        const uint8_t* source[1] = {rgb.data()};
        const int source_stride[1] = {even_width * 3};
        sws_scale(scaler.get(), source, source_stride, 0, even_height, picture->data, picture->linesize);
        picture->pts = encoded_;
        Check(avcodec_send_frame(encoder.get(), picture.get()), "encoding failed");
        write_packets();
        ++encoded_;
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (abandoned_) throw std::runtime_error("the video was abandoned before it was finished");
      }
      Check(avcodec_send_frame(encoder.get(), nullptr), "encoding failed");  // flush the encoder's delay
      write_packets();
      Check(av_write_trailer(format.get()), "cannot finish the file (the MP4's index)");
      Check(avio_closep(&format->pb), "cannot close the file");
    });
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = std::current_exception();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = true;
  queue_.clear();
  changed_.notify_all();
}

}  // namespace wobble::pipelines
