// bench/render: fixed views of an elevation store rendered with the LOD mesh
// and with the brute-force full-resolution mesh (every finest sample a
// vertex), side by side: quads, triangles, draw calls, LOD selection CPU time
// (cold: first frame, tiles loaded and errors measured; warm: later frames)
// and GPU frame time (draw calls to glFinish). Medians after a warm-up.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"

using namespace relief;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Measure {
  uint32_t quads = 0, draw_calls = 0;
  uint64_t triangles = 0;
  double cold_ms = 0, warm_ms = 0, gpu_ms = 0, max_error = 0;
};

Result<Measure> measure(const tiles::Store& store, const lod::View& view, int mesh_level, bool full,
                        int runs) {
  const lod::MeshTopology mesh(mesh_level);
  lod::TerrainModel terrain(&store, mesh, uint64_t{2} << 30);
  lod::SelectionOptions o;
  o.pixel_error = 1;
  o.full_resolution = full;
  Measure m;
  auto first = RELIEF_TRY(lod::select_quads(view, terrain, o));
  m.cold_ms = first.stats.seconds * 1e3;
  std::vector<double> warm;
  for (int r = 0; r < std::max(runs, 5); ++r) {
    auto s = RELIEF_TRY(lod::select_quads(view, terrain, o));
    warm.push_back(s.stats.seconds * 1e3);
  }
  m.warm_ms = median(warm);
  m.quads = first.stats.quads;
  m.max_error = first.stats.max_error_pixels;
  auto target = RELIEF_TRY(render::make_offscreen_target(view.width, view.height));
  auto renderer = RELIEF_TRY(render::TerrainRenderer::create(terrain, nullptr));
  std::vector<double> gpu;
  for (int r = 0; r <= runs; ++r) {
    auto f = RELIEF_TRY(renderer->draw(view, first, *target, {}));
    if (r > 0) gpu.push_back(f.gpu_seconds * 1e3);  // the first uploads textures
    m.triangles = f.triangles;
    m.draw_calls = f.draw_calls;
  }
  m.gpu_ms = median(gpu);
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: render_bench STORE\n");
    return 2;
  }
  auto store = tiles::Store::open(argv[1]);
  if (!store) {
    std::fprintf(stderr, "%s\n", store.error().message.c_str());
    return 1;
  }
  auto context = render::GlContext::create_headless();
  if (!context) {
    std::fprintf(stderr, "%s\n", context.error().message.c_str());
    return 1;
  }
  std::printf(
      "renderer: %s; 1280x720, pixel error 1, LOD mesh level 4, brute force: every finest sample\n",
      (*context)->renderer().c_str());
  struct ViewCase {
    const char* name;
    lod::Camera camera;
  };
  const ViewCase views[] = {
      {"globe", {1.5, 30, 12e6, 0, -90, 0, 60, 1280, 720}},
      {"regional oblique", lod::look_at(1.5, 42.5, 1500, 60000, 20, -35, 60, 1280, 720)},
      {"low flight to the horizon", {1.05, 42.05, 2300, 35, -4, 0, 60, 1280, 720}},
  };
  std::printf("%-27s %-6s %8s %11s %6s %10s %10s %9s %8s\n", "view", "mesh", "quads", "triangles",
              "draws", "select ms", "(cold ms)", "gpu ms", "err px");
  for (const ViewCase& v : views) {
    auto view = lod::make_view(v.camera);
    if (!view) return 1;
    auto lod_m = measure(*store, *view, 4, false, 3);
    auto full_m = measure(*store, *view, 8, true, 1);
    if (!lod_m || !full_m) {
      std::fprintf(stderr, "%s\n", (!lod_m ? lod_m.error() : full_m.error()).message.c_str());
      return 1;
    }
    for (const auto& [label, m] : {std::pair{"LOD", *lod_m}, std::pair{"full", *full_m}}) {
      std::printf("%-27s %-6s %8u %11llu %6u %10.2f %10.1f %9.1f %8.2f\n", v.name, label, m.quads,
                  static_cast<unsigned long long>(m.triangles), m.draw_calls, m.warm_ms, m.cold_ms,
                  m.gpu_ms, m.max_error);
    }
    std::printf("%-27s ratio: %.1fx fewer triangles, %.1fx less GPU time\n", v.name,
                static_cast<double>(full_m->triangles) /
                    static_cast<double>(std::max<uint64_t>(1, lod_m->triangles)),
                full_m->gpu_ms / std::max(1e-9, lod_m->gpu_ms));
  }
  return 0;
}
