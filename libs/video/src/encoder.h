#pragma once
// The encoder behind VideoWriter: RGBA frames -> swscale (yuv420p) -> libx264
// -> the MP4 muxer, into one file. Private to libs/video.
//
// It lives in a module of its own (librelief_video_ffmpeg.so, encoder.cpp),
// loaded on the first movie: linked into relief, FFmpeg's ~90 shared
// libraries would add ~16 MB to the resident set of every command (`relief
// build` included, whose memory budget covers the whole process).
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "relief/base/result.h"
#include "relief/video/video_writer.h"

namespace relief::video {

class Encoder {
 public:
  virtual ~Encoder() = default;  // closes the file, complete or not
  virtual Status encode(std::span<const uint8_t> rgba, RowOrder rows) = 0;
  // Drains the encoder, writes the MP4 index and closes the file.
  virtual Status finish() = 0;
};

// Opens an encoder writing to `file`; messages name `name` (the movie's
// final path). `options` passed check_options().
using OpenEncoder = Result<std::unique_ptr<Encoder>> (*)(const std::string& file,
                                                         const std::string& name, int width,
                                                         int height, double fps,
                                                         const VideoOptions& options);

// The module's one entry point (dlsym), of type OpenEncoder.
inline constexpr const char* kOpenEncoderSymbol = "relief_video_open_encoder";

}  // namespace relief::video
