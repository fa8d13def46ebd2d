#include "web_js.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

namespace relief::testing {

std::string run_node(const std::vector<std::string>& args, int& status) {
  std::string command = "node";
  for (const auto& a : args) command += " '" + a + "'";
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[65536];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  status = pclose(pipe);
  return out;
}

std::vector<LatticePoint> random_lattice_points(const tiles::Store& store,
                                                const web::TerrainTiler& tiler, int level,
                                                size_t count, uint32_t seed) {
  const double d = store.grid().sample_spacing(level);
  const auto keys = tiler.available_tiles(level);
  std::mt19937 random(seed);
  std::vector<LatticePoint> points;
  while (points.size() < count) {
    const web::TerrainKey k = keys[random() % keys.size()];
    const int p = 1 + static_cast<int>(random() % 255), q = 1 + static_cast<int>(random() % 255);
    const geo::GeoBox b = k.bounds();
    const double lon = b.west + ((p * 32767 + 128) >> 8) / 32767.0 * b.width();
    const double lat = b.south + (((256 - q) * 32767 + 128) >> 8) / 32767.0 * b.height();
    double sum = 0;
    int valid = 0;
    for (const double dx : {-d / 2, d / 2}) {
      for (const double dy : {-d / 2, d / 2}) {
        auto v = store.sample(lon + dx, lat + dy, level);
        if (!v) {
          ADD_FAILURE() << v.error().message;
          return points;
        }
        if (*v) sum += **v, ++valid;
      }
    }
    if (valid == 4) points.push_back({lon, lat, sum / 4});
  }
  return points;
}

}  // namespace relief::testing
