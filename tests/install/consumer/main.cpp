// Opens a store with an installed relief::tiles, reads its finest tiles and
// samples an elevation: the public headers, the static library and its
// private codec libraries all have to arrive through find_package(relief).
#include <cmath>
#include <cstdio>

#include "relief/tiles/codec.h"
#include "relief/tiles/store.h"

namespace {
int fail(const std::string& what) {
  std::fprintf(stderr, "consumer: %s\n", what.c_str());
  return 1;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return fail("usage: consumer STORE");
  auto store = relief::tiles::Store::open(argv[1]);
  if (!store) return fail(store.error().message);
  const auto& m = store->manifest();
  const auto& finest = store->index(m.max_level);
  if (finest.size() == 0) return fail("no tile on the finest level");
  for (const auto& entry : finest.entries()) {
    auto tile = store->read_tile(entry.key);
    if (!tile) return fail(tile.error().message);
    // A lossy round trip through another codec (LERC) than the store's.
    relief::tiles::CodecOptions lerc{.codec = relief::tiles::Codec::Lerc, .max_error = 0.5};
    auto bytes = relief::tiles::encode(tile->raster, lerc);
    if (!bytes) return fail(bytes.error().message);
    auto back = relief::tiles::decode(lerc.codec, *bytes, tile->raster.type(), tile->raster.bands(),
                                      tile->raster.width(), tile->raster.height());
    if (!back) return fail(back.error().message);
  }
  const double lon = (m.extent.west + m.extent.east) / 2,
               lat = (m.extent.south + m.extent.north) / 2;
  auto value = store->sample(lon, lat, m.max_level);
  if (!value) return fail(value.error().message);
  if (!*value || !(**value >= m.stats.min && **value <= m.stats.max)) {
    return fail("the sample at the extent's centre is missing or outside the store's range");
  }
  std::printf("%zu tiles on level %d, %.1f %s at (%.3f, %.3f)\n", finest.size(), m.max_level,
              static_cast<double>(**value), m.units.c_str(), lon, lat);
  return 0;
}
