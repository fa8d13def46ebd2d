// lod::refine(): one frame's refinement from start to end (its parts: refiner.h).
#include "relief/lod/refine.h"

#include <chrono>
#include <vector>

#include "refiner.h"

namespace relief::lod {

Result<RefinedMesh> refine(const View& view, TerrainModel& terrain, const Selection& selection,
                           const RefineOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = refinement::thread_cpu_seconds();
  RefineCache local(0);
  RefineCache& cache = options.cache ? *options.cache : local;
  // The marks' blocks and the step tables stay with the thread for its next frame.
  thread_local SlotMarks marks;
  thread_local refinement::StepTables steps;
  thread_local size_t last_indices = 0;
  RefineOptions o = options;
  // With the criteria evaluated elsewhere nothing is recorded: a recorded
  // decision's margins need the CPU's terms of its criterion (pixels() with
  // `out`), which would evaluate every criterion a second time.
  if (o.criteria) o.history = nullptr;
  RefineHistory::Impl* history = o.history ? &o.history->impl() : nullptr;
  if (history) {
    const RefineHistory::Impl::Seen seen{view.eye, view.right, view.up, view.forward,
                                         options.pixel_error};
    if (history->dormant > 0 && history->seen == seen) {  // stopped: record from this frame
      history->dormant = 0;
      history->judged = false;
      history->low = 0;
      history->spell = 0;
    }
    history->seen = seen;
  }
  const bool asleep = history && history->dormant > 0;
  if (asleep) {  // decided from scratch, nothing recorded
    --history->dormant;
    o.history = nullptr;
  }
  std::vector<refinement::Quad> quads(selection.quads.size());
  double criteria_seconds = 0;
  refinement::Refiner r(view, terrain, selection, o, cache.impl(), marks, steps, quads);
  RELIEF_CHECK(r.prepare());
  RefinedMesh mesh;
  double lanes_cpu = 0;                       // of the lanes' threads other than this one
  std::vector<std::vector<uint8_t>> classes;  // RefineOptions::criteria's
  if (o.criteria && !r.reuse_all()) {
    const auto at = std::chrono::steady_clock::now();
    RELIEF_CHECK(r.evaluate_criteria(*o.criteria, classes));
    criteria_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - at).count();
  }
  if (r.reuse_all()) {
    mesh = r.reused_mesh();
  } else {
    const size_t lanes = refinement::lane_count(o, selection);
    if (lanes > 1) {
      mesh = refinement::refine_in_lanes(r, selection, lanes, *o.executor, lanes_cpu);
    } else {
      if (o.variant == RefineVariant::kTopDown) {
        r.top_down();
      } else {
        r.bottom_up();
      }
      mesh = r.mesh(last_indices);
      last_indices = mesh.indices.size();
    }
    if (o.executor) refinement::remember_work(selection, mesh);  // for deal() in a later frame
  }
  r.save_history(mesh);
  cache.impl().end_frame(terrain);
  if (o.history) refinement::judge_reuse(*history, mesh.stats);
  mesh.stats.history_asleep = asleep;
  mesh.stats.criteria_seconds = criteria_seconds;
  mesh.stats.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  mesh.stats.cpu_seconds = refinement::thread_cpu_seconds() - cpu_start + lanes_cpu;
  return mesh;
}

}  // namespace relief::lod
