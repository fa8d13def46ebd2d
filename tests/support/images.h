#pragma once
// Frames written by `relief render`, read back for comparisons.
#include <cstdint>
#include <filesystem>
#include <vector>

namespace relief::testing {

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
};

// The PNG at `path`, which must be width x height RGBA (a test failure and a
// black image otherwise).
Image read_png(const std::filesystem::path& path, int width, int height);

// Pixels of exactly this colour.
size_t count_colour(const Image& image, uint8_t r, uint8_t g, uint8_t b);

}  // namespace relief::testing
