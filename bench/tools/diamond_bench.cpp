// bench/tools/diamond_bench: what measuring one tile's diamond errors costs
// (lod::measure_diamonds, done by the loaders' threads as each elevation tile
// arrives, or by the render thread when a frame needs a tile they have not
// prepared). Reads up to COUNT tiles of LEVEL of a store (the first in index
// order), measures each PASSES times, and prints the median over tiles of each
// tile's fastest pass in milliseconds
// and a hash of every error, low and high: two builds that print the
// same hash measured the same values.
#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "diamond_errors.h"
#include "relief/tiles/store.h"

using namespace relief;

int main(int argc, char** argv) {
  if (argc < 3 || argc > 5) {
    std::fprintf(stderr, "usage: diamond_bench STORE LEVEL [COUNT [PASSES]]\n");
    return 2;
  }
  const int level = std::atoi(argv[2]);
  const size_t count = argc >= 4 ? std::strtoul(argv[3], nullptr, 10) : 16;
  const int passes = argc >= 5 ? std::atoi(argv[4]) : 3;
  auto store = tiles::Store::open(argv[1]);
  if (!store) {
    std::fprintf(stderr, "%s\n", store.error().message.c_str());
    return 1;
  }
  const tiles::TileShape& shape = store->tile_shape();
  const int border = shape.border, width = shape.width - 2 * border;
  const lod::MarkGrid grid(std::countr_zero(static_cast<uint32_t>(width)));
  std::vector<tiles::Raster> rasters;
  for (const tiles::IndexEntry& e : store->index(level).entries()) {
    if (rasters.size() == count) break;
    auto tile = store->read_tile(e.key);
    if (!tile) {
      std::fprintf(stderr, "%s\n", tile.error().message.c_str());
      return 1;
    }
    rasters.push_back(std::move(tile->raster));
  }
  if (rasters.empty()) {
    std::fprintf(stderr, "%s: no tiles on level %d\n", argv[1], level);
    return 1;
  }
  std::vector<double> ms;
  uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a over every DiamondError
  for (const tiles::Raster& raster : rasters) {
    std::vector<double> runs;
    lod::DiamondErrors errors;
    for (int p = 0; p < passes; ++p) {
      const auto start = std::chrono::steady_clock::now();
      errors = lod::measure_diamonds(grid, raster, border);
      runs.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
    }
    std::sort(runs.begin(), runs.end());
    ms.push_back(runs.front());
    if (ms.size() == 1)
      std::printf("%llu bytes of errors per tile\n",
                  static_cast<unsigned long long>(errors.bytes()));
    for (const lod::DiamondError& d : errors.at) {
      uint64_t bits = 0;
      std::memcpy(&bits, &d.error, sizeof d.error);
      hash = (hash ^ (bits | uint64_t(uint16_t(d.lo)) << 32 | uint64_t(uint16_t(d.hi)) << 48)) *
             0x100000001b3ull;
    }
  }
  std::sort(ms.begin(), ms.end());
  double total = 0;
  for (const double m : ms) total += m;
  std::printf(
      "%zu tiles of level %d (%dx%d): measure ms/tile median %.2f mean %.2f; hash %016llx\n",
      ms.size(), level, width, shape.height - 2 * border, ms[ms.size() / 2],
      total / static_cast<double>(ms.size()), static_cast<unsigned long long>(hash));
  return 0;
}
