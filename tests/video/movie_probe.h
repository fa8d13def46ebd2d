#pragma once
// Reading movies back in the tests with FFmpeg's command-line tools (the
// independent decoder; relief's own FFmpeg use stays in libs/video).
#include <filesystem>
#include <string>
#include <vector>

#include "images.h"

namespace relief::testing {

struct MovieInfo {
  std::string codec, pix_fmt;
  int width = 0, height = 0;
  long frames = 0;      // counted by decoding (ffprobe -count_frames)
  double duration = 0;  // of the container, seconds
  std::string frame_rate;
};

// ffprobe's view of `movie`; a test failure (and an empty info) if it cannot read it.
MovieInfo probe_movie(const std::filesystem::path& movie);

// Every frame of `movie` decoded by ffmpeg to RGBA, top row first.
std::vector<Image> decode_movie(const std::filesystem::path& movie, int width, int height);

// Peak signal-to-noise ratio over the RGB channels, in dB (infinite when equal).
double psnr(const Image& a, const Image& b);

}  // namespace relief::testing
