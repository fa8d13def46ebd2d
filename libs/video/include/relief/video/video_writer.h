#pragma once
// Movies: RGBA frames in, an H.264 MP4 out (docs/video.md).
//
// write() hands a frame to an encoding thread through a small bounded queue,
// so the caller renders the next frame while the previous one is converted
// to yuv420p and encoded; it blocks only when the queue is full. The movie is
// written to a temporary file beside the target and renamed onto it by
// finish(): a failed or interrupted export never leaves a partial movie
// under the final name.
//
// One thread calls open/write/finish; the encoder's thread is internal.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "relief/base/result.h"

namespace relief::video {

struct VideoOptions {
  std::string codec = "h264";  // see codec_names()
  int crf = 18;                // constant rate factor: 0 (lossless) .. 51, lower is better
  // x264's speed against size at the same quality: ultrafast .. veryslow
  // (preset_names()). veryfast: on two cores "medium" took a quarter of all
  // CPU time of an export and slowed it to 77 % of rendering alone (90 % with
  // veryfast), for a file of the same size over the Pyrenees (docs/video.md).
  std::string preset = "veryfast";
  int queue_frames = 3;  // frames waiting for the encoder before write() blocks
};

// The codecs `codec` may name, for help texts and error messages.
std::string codec_names();
// The presets `preset` may name, fastest first.
std::string preset_names();
// Fails with a one-line message naming the option if `options` is not usable.
Status check_options(const VideoOptions& options);

// How a frame's rows are ordered: top first (images, PNGs) or bottom first
// (as OpenGL reads a framebuffer back; the encoder flips them for free).
enum class RowOrder { top_first, bottom_first };

struct VideoStats {
  uint64_t frames = 0;
  uint64_t bytes = 0;             // of the finished file
  double encode_seconds = 0;      // on the encoder's thread (conversion and encoding)
  double write_wait_seconds = 0;  // write() blocked on a full queue (encoding not hidden)
};

class VideoWriter {
 public:
  // Creates the temporary file beside `path` (and the parent directories) and
  // starts the encoder. `width` and `height` must be even (yuv420p), `fps` > 0.
  static Result<std::unique_ptr<VideoWriter>> open(const std::filesystem::path& path, int width,
                                                   int height, double fps,
                                                   const VideoOptions& options = {});
  // Without finish(): the encoder stops and the temporary file is removed.
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // One frame, width * height * 4 bytes, rows in `rows` order. Fails if the
  // encoder has failed (the error names the file).
  Status write(std::vector<uint8_t> rgba, RowOrder rows = RowOrder::top_first);
  // A frame buffer to fill and pass to write(): one the encoder is done
  // with when there is one (no allocation, no page faults on the render
  // thread), else a new one. Its contents are undefined.
  std::vector<uint8_t> take_buffer();
  // Flushes the encoder, completes the file and renames it onto the path.
  Result<VideoStats> finish();

  struct Impl;

 private:
  explicit VideoWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace relief::video
