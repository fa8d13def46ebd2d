#include "movie_probe.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include <nlohmann/json.hpp>

#include "test_support.h"

namespace relief::testing {

namespace {

std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Stdout of a shell command that must succeed.
std::string output_of(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) {
    ADD_FAILURE() << "cannot run " << command;
    return out;
  }
  char buffer[1 << 16];
  for (size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  EXPECT_EQ(pclose(pipe), 0) << command;
  return out;
}

}  // namespace

MovieInfo probe_movie(const std::filesystem::path& movie) {
  const nlohmann::json j = nlohmann::json::parse(
      output_of("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                "stream=codec_name,pix_fmt,width,height,nb_read_frames,r_frame_rate "
                "-show_entries format=duration -of json " +
                quoted(movie.string())),
      nullptr, false);
  MovieInfo info;
  if (j.is_discarded() || j["streams"].size() != 1) {
    ADD_FAILURE() << "ffprobe cannot read " << movie;
    return info;
  }
  const nlohmann::json& s = j["streams"][0];
  info.codec = s.value("codec_name", "");
  info.pix_fmt = s.value("pix_fmt", "");
  info.width = s.value("width", 0);
  info.height = s.value("height", 0);
  info.frames = std::stol(s.value("nb_read_frames", "0"));
  info.frame_rate = s.value("r_frame_rate", "");
  info.duration = std::stod(j["format"].value("duration", "0"));
  return info;
}

std::vector<Image> decode_movie(const std::filesystem::path& movie, int width, int height) {
  const std::string raw =
      output_of("ffmpeg -v error -i " + quoted(movie.string()) + " -f rawvideo -pix_fmt rgba -");
  const size_t frame_bytes = static_cast<size_t>(width) * height * 4;
  EXPECT_EQ(raw.size() % frame_bytes, 0u) << movie;
  std::vector<Image> frames;
  for (size_t at = 0; at + frame_bytes <= raw.size(); at += frame_bytes) {
    frames.push_back(
        {width, height, std::vector<uint8_t>(raw.begin() + at, raw.begin() + at + frame_bytes)});
  }
  return frames;
}

double psnr(const Image& a, const Image& b) {
  EXPECT_EQ(a.rgba.size(), b.rgba.size());
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < std::min(a.rgba.size(), b.rgba.size()); ++i) {
    if (i % 4 == 3) continue;  // alpha
    const double d = double(a.rgba[i]) - double(b.rgba[i]);
    sum += d * d;
    ++n;
  }
  if (sum == 0) return std::numeric_limits<double>::infinity();
  return 10 * std::log10(255.0 * 255.0 / (sum / double(n)));
}

}  // namespace relief::testing
