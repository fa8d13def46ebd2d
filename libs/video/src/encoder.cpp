#include "encoder.h"

#include <cassert>
#include <type_traits>

#include <fmt/format.h>

#include "codecs.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace relief::video {

namespace {

std::string av_text(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

class FfmpegEncoder final : public Encoder {
 public:
  std::string name;
  int width = 0, height = 0;
  AVFormatContext* format = nullptr;
  AVCodecContext* codec = nullptr;
  AVStream* stream = nullptr;
  SwsContext* sws = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  int64_t next_pts = 0;

  ~FfmpegEncoder() override {
    sws_freeContext(sws);
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&codec);
    if (format) {
      if (format->pb) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }

  Status error(const std::string& what, int code) const {
    return fail(fmt::format("{}: {}: {}", name, what, av_text(code)));
  }

  // Sends a frame (null: end of stream) and muxes every packet it yields.
  Status send(const AVFrame* f) {
    if (int rc = avcodec_send_frame(codec, f); rc < 0) return error("encoding", rc);
    for (;;) {
      const int rc = avcodec_receive_packet(codec, packet);
      if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return {};
      if (rc < 0) return error("encoding", rc);
      if (packet->duration == 0) packet->duration = 1;  // one frame: the last one has a length
      av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
      packet->stream_index = stream->index;
      if (int w = av_interleaved_write_frame(format, packet); w < 0) return error("writing", w);
    }
  }

  Status open(const std::string& file, double fps, const VideoOptions& options) {
    const char* encoder_name = nullptr;
    for (const CodecName& c : kCodecs) {
      if (options.codec == c.name) encoder_name = c.encoder;
    }
    assert(encoder_name);  // check_options() passed
    const AVCodec* encoder = avcodec_find_encoder_by_name(encoder_name);
    if (!encoder) return fail(fmt::format("{}: FFmpeg has no {} encoder", name, encoder_name));
    if (int rc = avformat_alloc_output_context2(&format, nullptr, "mp4", file.c_str()); rc < 0) {
      return error("cannot set up MP4 output", rc);
    }
    codec = avcodec_alloc_context3(encoder);
    frame = av_frame_alloc();
    packet = av_packet_alloc();
    if (!codec || !frame || !packet) return fail(name + ": out of memory");
    const AVRational rate = av_d2q(fps, 1 << 20);
    codec->width = width;
    codec->height = height;
    codec->pix_fmt = AV_PIX_FMT_YUV420P;
    codec->time_base = av_inv_q(rate);
    codec->framerate = rate;
    // swscale's RGB to YUV is BT.601, limited range: say so, so that players
    // (and the tests' decoder) convert back with the same matrix.
    codec->colorspace = AVCOL_SPC_SMPTE170M;
    codec->color_range = AVCOL_RANGE_MPEG;
    if (format->oformat->flags & AVFMT_GLOBALHEADER) codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    AVDictionary* private_options = nullptr;
    av_dict_set(&private_options, "crf", std::to_string(options.crf).c_str(), 0);
    av_dict_set(&private_options, "preset", options.preset.c_str(), 0);
    const int opened = avcodec_open2(codec, encoder, &private_options);
    av_dict_free(&private_options);
    if (opened < 0) return error(fmt::format("cannot open the {} encoder", encoder_name), opened);
    stream = avformat_new_stream(format, nullptr);
    if (!stream) return fail(name + ": out of memory");
    stream->time_base = codec->time_base;
    stream->avg_frame_rate = rate;
    if (int rc = avcodec_parameters_from_context(stream->codecpar, codec); rc < 0) {
      return error("stream parameters", rc);
    }
    frame->format = codec->pix_fmt;
    frame->width = width;
    frame->height = height;
    if (int rc = av_frame_get_buffer(frame, 0); rc < 0) return error("frame buffer", rc);
    sws = sws_getContext(width, height, AV_PIX_FMT_RGBA, width, height, AV_PIX_FMT_YUV420P,
                         SWS_BICUBIC | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INP, nullptr, nullptr,
                         nullptr);
    if (!sws) return fail(name + ": swscale cannot convert RGBA to yuv420p at this size");
    if (int rc = avio_open(&format->pb, file.c_str(), AVIO_FLAG_WRITE); rc < 0) {
      return error("cannot create", rc);
    }
    // The index at the front: players start before the whole file has arrived.
    AVDictionary* muxer_options = nullptr;
    av_dict_set(&muxer_options, "movflags", "+faststart", 0);
    const int header = avformat_write_header(format, &muxer_options);
    av_dict_free(&muxer_options);
    if (header < 0) return error("writing the MP4 header", header);
    return {};
  }

  Status encode(std::span<const uint8_t> rgba, RowOrder rows) override {
    assert(rgba.size() == static_cast<size_t>(width) * static_cast<size_t>(height) * 4);
    if (int rc = av_frame_make_writable(frame); rc < 0) return error("frame buffer", rc);
    // Bottom-up rows are read from the last row with a negative stride:
    // swscale flips them while converting, no copy.
    const size_t row = static_cast<size_t>(width) * 4;
    const bool flip = rows == RowOrder::bottom_first;
    const uint8_t* const planes[1] = {flip ? rgba.data() + row * static_cast<size_t>(height - 1)
                                           : rgba.data()};
    const int strides[1] = {flip ? -width * 4 : width * 4};
    sws_scale(sws, planes, strides, 0, height, frame->data, frame->linesize);
    frame->pts = next_pts++;
    return send(frame);
  }

  Status finish() override {
    RELIEF_CHECK(send(nullptr));
    if (int rc = av_write_trailer(format); rc < 0) return error("writing the MP4 index", rc);
    if (int rc = avio_closep(&format->pb); rc < 0) return error("writing", rc);
    return {};
  }
};

Result<std::unique_ptr<Encoder>> open_encoder(const std::string& file, const std::string& name,
                                              int width, int height, double fps,
                                              const VideoOptions& options) {
  av_log_set_level(AV_LOG_QUIET);  // failures come back as values; x264 would chat on stderr
  auto encoder = std::make_unique<FfmpegEncoder>();
  encoder->name = name;
  encoder->width = width;
  encoder->height = height;
  RELIEF_CHECK(encoder->open(file, fps, options));
  return encoder;
}

}  // namespace

}  // namespace relief::video

// Checked against the type VideoWriter casts the symbol to.
extern "C" [[gnu::visibility("default")]] relief::Result<std::unique_ptr<relief::video::Encoder>>
relief_video_open_encoder(const std::string& file, const std::string& name, int width, int height,
                          double fps, const relief::video::VideoOptions& options) {
  return relief::video::open_encoder(file, name, width, height, fps, options);
}
static_assert(std::is_same_v<decltype(&relief_video_open_encoder), relief::video::OpenEncoder>);
