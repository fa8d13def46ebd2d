// bench/refine-gl: edge-mark refinement of fixed views four ways, side by
// side in one run: top-down on the CPU (the default), bottom-up on the CPU
// (every diamond decided, the seed's reference), and both with every split
// criterion evaluated by the GL compute shader (render::GlRefineCriteria) in
// this process's GL context. Median of 3 warm refinements after a warm-up
// one (tiles read, diamond errors measured); the four meshes must be equal
// (the bench fails otherwise). Prints per view the quads, triangles,
// diamonds (bottom-up decides them all), the times, the shader's time and
// what is left of top-down with its classes (the walk), the diamonds the
// shader left to the CPU and the bytes uploaded per warm refinement with the
// shader (the diamond errors stay on the GPU); with a third argument,
// markdown rows appended to that file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "lod_bench_setup.h"
#include "relief/lod/criterion_evaluator.h"
#include "relief/lod/refine.h"
#include "relief/lod/selection.h"
#include "relief/render/gl_refine_criteria.h"
#include "relief/render/terrain_renderer.h"

using namespace relief;

namespace {

constexpr int kRuns = 3;

struct Timing {
  double ms = 0, criteria_ms = 0;
  uint64_t marks = 0, near = 0, triangles = 0;
  double uploaded_mb = 0;  // GL: to the GPU per warm refinement
};

Result<Timing> time_refinement(const lod::View& view, lod::TerrainModel& terrain,
                               const lod::Selection& selection, lod::RefineCache& cache,
                               lod::RefineVariant variant, render::GlRefineCriteria* criteria,
                               const std::vector<uint32_t>& expected) {
  lod::RefineOptions o;
  o.pixel_error = 1;
  o.variant = variant;
  o.cache = &cache;
  o.criteria = criteria;
  std::vector<double> ms, criteria_ms;
  Timing t;
  uint64_t uploaded = 0;
  for (int r = 0; r <= kRuns; ++r) {
    if (r == 1 && criteria) uploaded = criteria->bytes_uploaded();
    const lod::RefinedMesh m = RELIEF_TRY(lod::refine(view, terrain, selection, o));
    if (!expected.empty() && m.indices != expected) {
      return fail("another mesh than top-down's on the CPU");
    }
    if (r == 0) continue;  // the warm-up
    ms.push_back(m.stats.seconds * 1e3);
    criteria_ms.push_back(m.stats.criteria_seconds * 1e3);
    t.marks = m.stats.marks_evaluated;
    t.near = m.stats.marks_near;
    t.triangles = m.triangles();
  }
  std::sort(ms.begin(), ms.end());
  std::sort(criteria_ms.begin(), criteria_ms.end());
  t.ms = ms[ms.size() / 2];
  t.criteria_ms = criteria_ms[criteria_ms.size() / 2];
  if (criteria) t.uploaded_mb = double(criteria->bytes_uploaded() - uploaded) / kRuns / 1e6;
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  int exit_code = 0;
  auto bench = bench::open_lod_bench(argc, argv, "criteria_bench", exit_code);
  if (!bench) return exit_code;
  const tiles::Store& store = *bench->store;
  FILE* markdown = bench->markdown;
  auto criteria = render::GlRefineCriteria::create();
  if (!criteria) {
    std::fprintf(stderr, "%s\n", criteria.error().message.c_str());
    return 1;
  }
  std::printf("renderer: %s; 1280x720, pixel error 1, one thread refining\n",
              bench->context->renderer().c_str());
  std::printf("%-27s %6s %10s %10s %9s %9s %9s %9s %9s %9s %6s %6s\n", "view", "quads", "triangles",
              "diamonds", "td ms", "bu ms", "GL bu ms", "GL td ms", "shader ms", "walk ms", "near",
              "MB up");
  for (const bench::ViewCase& v : bench->views) {
    auto view = lod::make_view(v.camera);
    if (!view) {
      std::fprintf(stderr, "%s: %s\n", v.name, view.error().message.c_str());
      return 1;
    }
    const lod::MeshTopology topology(4);
    lod::TerrainModel terrain(&store, topology, uint64_t{2} << 30);
    lod::RefineCache cache(uint64_t{2} << 30);
    lod::SelectionOptions so;
    so.pixel_error = 1;
    so.mode = lod::LodMode::edge_marks;
    so.neighbour_indices = true;
    auto selection = lod::select_quads(*view, terrain, so);
    if (!selection) {
      std::fprintf(stderr, "%s: %s\n", v.name, selection.error().message.c_str());
      return 1;
    }
    lod::RefineOptions o;
    o.cache = &cache;
    auto reference = lod::refine(*view, terrain, *selection, o);
    if (!reference) {
      std::fprintf(stderr, "%s: %s\n", v.name, reference.error().message.c_str());
      return 1;
    }
    const auto& expected = reference->indices;
    auto time = [&](lod::RefineVariant variant, render::GlRefineCriteria* c) {
      return time_refinement(*view, terrain, *selection, cache, variant, c, expected);
    };
    using enum lod::RefineVariant;
    const auto top_down = time(kTopDown, nullptr), bottom_up = time(kBottomUp, nullptr);
    const auto gl_bottom_up = time(kBottomUp, criteria->get());
    const auto gl_top_down = time(kTopDown, criteria->get());
    for (const auto* t : {&top_down, &bottom_up, &gl_bottom_up, &gl_top_down}) {
      if (!*t) {
        std::fprintf(stderr, "%s: %s\n", v.name, t->error().message.c_str());
        return 1;
      }
    }
    // The top-down walk with the shader's classes: what a GPU that evaluates
    // the criteria in no time would leave.
    const double walk = gl_top_down->ms - gl_top_down->criteria_ms;
    // One row, to the terminal and to the markdown table, in two formats.
    const auto row = [&](FILE* out, std::string_view format) {
      fmt::print(out, fmt::runtime(format), v.name, selection->quads.size(), top_down->triangles,
                 bottom_up->marks, top_down->ms, bottom_up->ms, gl_bottom_up->ms, gl_top_down->ms,
                 gl_top_down->criteria_ms, walk, gl_bottom_up->near + gl_top_down->near,
                 gl_top_down->uploaded_mb);
    };
    row(stdout,
        "{:<27} {:6} {:10} {:10} {:9.2f} {:9.1f} {:9.1f} {:9.1f} {:9.1f} {:9.2f} {:6} {:6.2f}\n");
    if (markdown) {
      row(markdown,
          "| {} | {} | {} | {} | {:.2f} ms | {:.1f} ms | {:.1f} ms | {:.1f} ms | {:.1f} ms | "
          "{:.2f} ms | {} | {:.2f} MB |\n");
    }
  }
  return bench::close_markdown(*bench, argv[3]) ? 0 : 1;
}
