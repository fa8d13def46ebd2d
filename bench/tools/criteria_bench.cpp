// bench/refine-gl: edge-mark refinement of fixed views three ways, side by
// side in one run: top-down on the CPU (the default), bottom-up on the CPU
// (every diamond decided, the seed's reference) and bottom-up with every
// split criterion evaluated by the GL compute shader
// (render::GlRefineCriteria) in this process's GL context. Median of 3 warm
// refinements after a warm-up one (tiles read, diamond errors measured); the
// three meshes must be equal (the bench fails otherwise). Prints per view the
// quads, diamonds decided, the times, the shader's share and the ratios; with
// a third argument, markdown rows appended to that file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
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
};

Result<Timing> time_refinement(const lod::View& view, lod::TerrainModel& terrain,
                               const lod::Selection& selection, lod::RefineCache& cache,
                               lod::RefineVariant variant, lod::CriterionEvaluator* criteria,
                               const std::vector<uint32_t>& expected) {
  lod::RefineOptions o;
  o.pixel_error = 1;
  o.variant = variant;
  o.cache = &cache;
  o.criteria = criteria;
  std::vector<double> ms, criteria_ms;
  Timing t;
  for (int r = 0; r <= kRuns; ++r) {
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
  std::printf("%-27s %6s %10s %12s %10s %12s %12s %10s %8s %10s\n", "view", "quads", "triangles",
              "top-down ms", "marks", "bottom-up ms", "GL b-u ms", "shader ms", "near", "GL/b-u");
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
    auto top_down = time_refinement(*view, terrain, *selection, cache, lod::RefineVariant::kTopDown,
                                    nullptr, expected);
    auto bottom_up = time_refinement(*view, terrain, *selection, cache,
                                     lod::RefineVariant::kBottomUp, nullptr, expected);
    auto gl = time_refinement(*view, terrain, *selection, cache, lod::RefineVariant::kBottomUp,
                              criteria->get(), expected);
    if (!top_down || !bottom_up || !gl) {
      const Error& e = !top_down ? top_down.error() : !bottom_up ? bottom_up.error() : gl.error();
      std::fprintf(stderr, "%s: %s\n", v.name, e.message.c_str());
      return 1;
    }
    std::printf("%-27s %6zu %10llu %12.2f %10llu %12.1f %12.1f %10.1f %8llu %9.2fx\n", v.name,
                selection->quads.size(), static_cast<unsigned long long>(top_down->triangles),
                top_down->ms, static_cast<unsigned long long>(bottom_up->marks), bottom_up->ms,
                gl->ms, gl->criteria_ms, static_cast<unsigned long long>(gl->near),
                gl->ms / bottom_up->ms);
    if (markdown) {
      std::fprintf(markdown,
                   "| %s | %zu | %llu | %.2f ms | %llu | %.1f ms | %.1f ms (shader %.1f ms, %llu "
                   "near) | %.2fx | %.0fx |\n",
                   v.name, selection->quads.size(),
                   static_cast<unsigned long long>(top_down->triangles), top_down->ms,
                   static_cast<unsigned long long>(bottom_up->marks), bottom_up->ms, gl->ms,
                   gl->criteria_ms, static_cast<unsigned long long>(gl->near),
                   gl->ms / bottom_up->ms, gl->ms / std::max(top_down->ms, 1e-3));
    }
  }
  return bench::close_markdown(*bench, argv[3]) ? 0 : 1;
}
