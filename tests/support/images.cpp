#include "images.h"

#include <gtest/gtest.h>

#include "relief/base/file_io.h"
#include "relief/tiles/codec.h"

namespace relief::testing {

Image read_png(const std::filesystem::path& path, int width, int height) {
  const Image black{width, height, std::vector<uint8_t>(static_cast<size_t>(width) * height * 4)};
  auto bytes = read_file(path, kNoSizeLimit);
  if (!bytes) {
    ADD_FAILURE() << path << ": " << bytes.error().message;
    return black;
  }
  auto raster =
      tiles::decode(tiles::Codec::Png, *bytes, tiles::SampleType::UInt8, 4, width, height);
  if (!raster) {
    ADD_FAILURE() << path << ": " << raster.error().message;
    return black;
  }
  Image img{width, height, {}};
  img.rgba.assign(raster->u8().begin(), raster->u8().end());
  return img;
}

size_t count_colour(const Image& image, uint8_t r, uint8_t g, uint8_t b) {
  size_t n = 0;
  for (size_t p = 0; p + 3 < image.rgba.size(); p += 4) {
    n += image.rgba[p] == r && image.rgba[p + 1] == g && image.rgba[p + 2] == b;
  }
  return n;
}

}  // namespace relief::testing
