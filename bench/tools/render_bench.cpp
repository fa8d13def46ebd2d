// bench/render: fixed views of an elevation store rendered with the LOD mesh
// and with the brute-force full-resolution mesh (every finest sample a
// vertex), side by side: quads, triangles, draw calls, LOD selection CPU time
// (cold: first frame, tiles loaded and errors measured; warm: median of 5
// later frames; edge marks also refined in lanes on one thread per core,
// RefineOptions::executor, the same mesh), GPU frame time (draw calls to glFinish, median of 3
// after a warm-up draw, for both meshes), the selection's screen-space error bound (its estimate of
// the largest error) and the error measured on random finest samples (lod/measured_error.h),
// triangles per screen pixel. VIEWS names the fixed views (pyrenees: the bundled SRTM pair;
// himalaya: the 4 x 6 degree SRTM3 block of ../shared/data/dem/srtm3-h44). With a third argument,
// the rows are also appended to that file as a markdown table.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lod_bench_setup.h"
#include "relief/base/parallel.h"
#include "relief/lod/measured_error.h"
#include "relief/lod/refine.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"

using namespace relief;

namespace {

std::string fmt_ms(double ms) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f ms", ms);
  return text;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Measure {
  uint32_t quads = 0, draw_calls = 0;
  uint64_t triangles = 0;
  double cold_ms = 0, warm_ms = 0, gpu_ms = 0, error_bound = 0, measured_error = 0;
  double warm_lanes_ms = NAN;  // edge marks: warm, refined in lanes
  size_t error_samples = 0;    // of the measured error: finest samples compared on screen
};

constexpr int kWarmSelections = 5;
constexpr int kGpuRuns = 3;
constexpr int kErrorSamples = 20000;
// Brute force beyond this many triangles is counted, not drawn: on llvmpipe a
// draw of the Himalaya block's 100-230 M triangles takes 20-40 s.
constexpr uint64_t kMaxDrawnTriangles = 50'000'000;

enum class Mesh { quads, edge_marks, brute_force };

// Selection (and, for edge marks, refinement) of one frame.
struct Frame {
  lod::Selection selection;
  std::optional<lod::RefinedMesh> refined;
  double seconds = 0;
};

Result<Frame> select_frame(const lod::View& view, lod::TerrainModel& terrain, Mesh mesh,
                           lod::RefineCache& cache, Executor* lanes = nullptr) {
  lod::SelectionOptions o;
  o.pixel_error = 1;
  o.full_resolution = mesh == Mesh::brute_force;
  o.mode = mesh == Mesh::edge_marks ? lod::LodMode::edge_marks : lod::LodMode::quads;
  o.neighbour_indices = mesh == Mesh::edge_marks;
  Frame f;
  f.selection = RELIEF_TRY(lod::select_quads(view, terrain, o));
  f.seconds = f.selection.stats.seconds;
  if (mesh == Mesh::edge_marks) {
    lod::RefineOptions ro;
    ro.pixel_error = 1;
    ro.cache = &cache;
    ro.executor = lanes;
    f.refined = RELIEF_TRY(lod::refine(view, terrain, f.selection, ro));
    f.seconds += f.refined->stats.seconds;
  }
  return f;
}

Result<Measure> measure(const tiles::Store& store, const lod::View& view, Mesh mesh) {
  const int full_level = static_cast<int>(std::log2(store.grid().height()));
  const lod::MeshTopology topology(mesh == Mesh::brute_force ? full_level : 4);
  lod::TerrainModel terrain(&store, topology, uint64_t{2} << 30);
  lod::RefineCache cache(uint64_t{2} << 30);
  Measure m;
  Frame first = RELIEF_TRY(select_frame(view, terrain, mesh, cache));
  m.cold_ms = first.seconds * 1e3;
  std::vector<double> warm;
  for (int r = 0; r < kWarmSelections; ++r) {
    warm.push_back(RELIEF_TRY(select_frame(view, terrain, mesh, cache)).seconds * 1e3);
  }
  m.warm_ms = median(warm);
  if (mesh == Mesh::edge_marks) {
    PooledExecutor lanes;
    warm.clear();
    for (int r = 0; r < kWarmSelections; ++r) {
      const Frame f = RELIEF_TRY(select_frame(view, terrain, mesh, cache, &lanes));
      if (f.refined->indices != first.refined->indices) {
        return fail("refinement in lanes made another mesh");
      }
      warm.push_back(f.seconds * 1e3);
    }
    m.warm_lanes_ms = median(warm);
  }
  m.quads = first.selection.stats.quads;
  m.error_bound = first.selection.stats.max_error_pixels;
  const lod::RefinedMesh* refined = first.refined ? &*first.refined : nullptr;
  if (refined) m.error_bound = 1;  // refinement splits every diamond over the threshold
  if (mesh != Mesh::brute_force) {
    const lod::MeasuredError e = RELIEF_TRY(lod::measure_screen_error(
        view, terrain, first.selection, store.manifest().extent, kErrorSamples, refined));
    m.measured_error = e.max_pixels;
    m.error_samples = e.samples;
  }
  if (mesh == Mesh::brute_force && first.selection.stats.triangles > kMaxDrawnTriangles) {
    m.triangles = first.selection.stats.triangles;
    m.draw_calls = 1;
    m.gpu_ms = NAN;
    return m;
  }
  auto target = RELIEF_TRY(render::make_offscreen_target(view.width, view.height));
  auto renderer = RELIEF_TRY(render::TerrainRenderer::create(terrain, nullptr));
  std::vector<double> gpu;
  for (int r = 0; r <= kGpuRuns; ++r) {
    auto f = RELIEF_TRY(renderer->draw(view, first.selection, *target, {}, refined));
    // Preparation (records, uploads) and the GPU's work to glFinish; the
    // first (warm-up) draw uploads the textures.
    if (r > 0) gpu.push_back((f.prepare_seconds + f.gpu_seconds) * 1e3);
    m.triangles = f.triangles;
    m.draw_calls = f.draw_calls;
  }
  m.gpu_ms = median(gpu);
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  int exit_code = 0;
  auto bench = bench::open_lod_bench(argc, argv, "render_bench", exit_code);
  if (!bench) return exit_code;
  const tiles::Store* store = &*bench->store;
  FILE* markdown = bench->markdown;
  std::printf(
      "renderer: %s; 1280x720, pixel error 1; edge marks (refined quads), quads (mesh level 4), "
      "brute force (every finest sample)\n",
      bench->context->renderer().c_str());
  const std::vector<bench::ViewCase>& views = bench->views;
  const unsigned cores = PooledExecutor().concurrency();
  std::printf("%-27s %-6s %8s %11s %7s %6s %10s %10s %10s %9s %8s %11s\n", "view", "mesh", "quads",
              "triangles", "tri/px", "draws", "select ms", fmt::format("{} thr ms", cores).c_str(),
              "(cold ms)", "gpu ms", "bound px", "measured px");
  for (const bench::ViewCase& v : views) {
    auto view = lod::make_view(v.camera);
    if (!view) {
      std::fprintf(stderr, "%s: %s\n", v.name, view.error().message.c_str());
      return 1;
    }
    auto edge_m = measure(*store, *view, Mesh::edge_marks);
    auto lod_m = measure(*store, *view, Mesh::quads);
    auto full_m = measure(*store, *view, Mesh::brute_force);
    if (!edge_m || !lod_m || !full_m) {
      const Error& e = !edge_m ? edge_m.error() : !lod_m ? lod_m.error() : full_m.error();
      std::fprintf(stderr, "%s: %s\n", v.name, e.message.c_str());
      return 1;
    }
    const double pixels = double(view->width) * view->height;
    for (const auto& [label, m] :
         {std::pair{"edges", *edge_m}, std::pair{"quads", *lod_m}, std::pair{"full", *full_m}}) {
      std::printf("%-27s %-6s %8u %11llu %7.2f %6u %10.2f %10.2f %10.1f %9.1f %8.2f %11.2f\n",
                  v.name, label, m.quads, static_cast<unsigned long long>(m.triangles),
                  double(m.triangles) / pixels, m.draw_calls, m.warm_ms, m.warm_lanes_ms, m.cold_ms,
                  m.gpu_ms, m.error_bound, m.measured_error);
    }
    if (markdown) {
      for (const auto& [label, m] :
           {std::pair{"edge marks", *edge_m}, std::pair{"quads", *lod_m}}) {
        const std::string lanes =
            std::isnan(m.warm_lanes_ms) ? std::string() : fmt::format("{:.2f} ms", m.warm_lanes_ms);
        std::fprintf(
            markdown,
            "| %s | %s | %u | %llu | %.2f | %u | %.2f ms | %s | %.1f ms | %.1f ms | %.2f px "
            "| %.2f px (%zu samples) |\n",
            label == std::string("edge marks") ? v.name : "", label, m.quads,
            static_cast<unsigned long long>(m.triangles), double(m.triangles) / pixels,
            m.draw_calls, m.warm_ms, lanes.c_str(), m.cold_ms, m.gpu_ms, m.error_bound,
            m.measured_error, m.error_samples);
      }
      const std::string gpu =
          std::isnan(full_m->gpu_ms) ? std::string("not drawn") : fmt_ms(full_m->gpu_ms);
      std::fprintf(markdown, "| | brute force | %u | %llu | %.2f | %u | | | | %s | | |\n",
                   full_m->quads, static_cast<unsigned long long>(full_m->triangles),
                   double(full_m->triangles) / pixels, full_m->draw_calls, gpu.c_str());
    }
    for (const auto& [label, m] : {std::pair{"edge marks", *edge_m}, std::pair{"quads", *lod_m}}) {
      std::printf("%-27s %s against brute force: %.1fx fewer triangles", v.name, label,
                  static_cast<double>(full_m->triangles) /
                      static_cast<double>(std::max<uint64_t>(1, m.triangles)));
      if (!std::isnan(full_m->gpu_ms)) {
        std::printf(", %.1fx less frame time", full_m->gpu_ms / std::max(1e-9, m.gpu_ms));
      }
      std::printf("\n");
    }
  }
  return bench::close_markdown(*bench, argv[3]) ? 0 : 1;
}
