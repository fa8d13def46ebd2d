#pragma once
// FFmpeg behind a small class: RGBA frames -> swscale (yuv420p) -> libx264 ->
// the MP4 muxer, into one file. Private to libs/video: no FFmpeg type leaves it.
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "relief/base/result.h"
#include "relief/video/video_writer.h"

namespace relief::video {

class Encoder {
 public:
  // Writes to `file`; messages name `name` (the movie's final path).
  static Result<std::unique_ptr<Encoder>> open(const std::string& file, const std::string& name,
                                               int width, int height, double fps,
                                               const VideoOptions& options);
  ~Encoder();  // closes the file, complete or not
  Encoder(const Encoder&) = delete;
  Encoder& operator=(const Encoder&) = delete;

  Status encode(std::span<const uint8_t> rgba);
  // Drains the encoder, writes the MP4 index and closes the file.
  Status finish();

  struct Impl;

 private:
  explicit Encoder(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::video
