#pragma once
// What the web tests that run JavaScript share: node itself, and points of
// the finest level's mesh lattice with the heights relief gives them.
#include <cstdint>
#include <string>
#include <vector>

#include "relief/tiles/store.h"
#include "relief/web/terrain_tiler.h"

namespace relief::testing {

// Runs node with the (shell-quoted) arguments; its stdout, `status` as
// pclose gives it.
std::string run_node(const std::vector<std::string>& args, int& status);

struct LatticePoint {
  double lon = 0, lat = 0;
  double height = 0;  // the mean of the 4 samples around the corner
};

// `count` random lattice corners of `level`'s available tiles, placed where
// the tiles' 16-bit u, v put them, each with all 4 samples around it valid
// (a test failure when the store cannot be read).
std::vector<LatticePoint> random_lattice_points(const tiles::Store& store,
                                                const web::TerrainTiler& tiler, int level,
                                                size_t count, uint32_t seed);

}  // namespace relief::testing
