// The viewer's panels (Dear ImGui), drawn over the terrain after each frame.
#include <algorithm>
#include <string>

#include <fmt/format.h>
#include <imgui.h>

#include "layer_panels.h"
#include "relief/base/units.h"
#include "relief/view/path_player.h"
#include "viewer_state.h"

namespace relief::window {

namespace {

void text(const std::string& s) {
  ImGui::TextUnformatted(s.c_str());
}

void layers(Viewer::Impl& v) {
  if (!ImGui::CollapsingHeader("Layers", ImGuiTreeNodeFlags_DefaultOpen)) return;
  text(v.elevation ? fmt::format("elevation: {}", v.elevation->root().filename().string())
                   : std::string("elevation: none (the ellipsoid)"));
  if (v.imagery) {
    ImGui::Checkbox("imagery", &v.imagery_wanted);
  } else {
    ImGui::TextDisabled("no imagery (--imagery STORE)");
  }
}

void level_of_detail(Viewer::Impl& v) {
  if (!ImGui::CollapsingHeader("Level of detail", ImGuiTreeNodeFlags_DefaultOpen)) return;
  auto still = static_cast<float>(v.scene_options.selection.pixel_error);
  if (ImGui::SliderFloat("pixel error", &still, 0.25f, 16.0f, "%.2f px",
                         ImGuiSliderFlags_Logarithmic)) {
    v.scene_options.selection.pixel_error = still;
  }
  bool relax = v.options.speed_lod.enabled;
  if (ImGui::Checkbox("relax with speed", &relax)) {
    v.options.speed_lod.enabled = relax;
    v.speed_lod = view::SpeedLod(v.options.speed_lod);
  }
  auto fps = static_cast<float>(
      v.options.frame_budget.target_ms > 0 ? 1e3 / v.options.frame_budget.target_ms : 0.0);
  if (ImGui::SliderFloat("target fps", &fps, 0.0f, 120.0f, fps > 0 ? "%.0f" : "off")) {
    v.options.frame_budget.target_ms = fps > 0 ? 1e3 / fps : 0;
    v.frame_budget = view::FrameBudget(v.options.frame_budget);
  }
  text(fmt::format("threshold now {:.2f} px (speed x{:.2f}, frame budget x{:.2f})", v.threshold,
                   v.speed_lod.factor(), v.frame_budget.factor()));
  if (ImGui::Checkbox("wireframe", &v.scene_options.render.wireframe)) {
    v.scene->set_render_options(v.scene_options.render);
  }
  // The last selection keeps being drawn while the camera moves: its
  // culling and detail seen from outside.
  if (ImGui::Checkbox("freeze selection", &v.frozen)) v.scene->set_selection_frozen(v.frozen);
}

void loader_lines(const char* name, stream::TileLoader* loader, const LoadRate& rate) {
  if (!loader) return;
  const stream::LoaderStats s = loader->stats();
  text(fmt::format("{} (L2): {} of {}", name, format_bytes(s.resident_bytes),
                   format_bytes(s.memory_budget)));
  ImGui::ProgressBar(
      s.memory_budget ? static_cast<float>(s.resident_bytes) / static_cast<float>(s.memory_budget)
                      : 0.0f,
      ImVec2(-1, 0), "");
  text(fmt::format("  {} tiles, queued {}, in flight {}", s.resident_tiles, s.queued, s.in_flight));
  text(fmt::format("  loads {} ({:.1f}/s), failures {} ({:.1f}/s)", s.loaded, rate.loads_per_s,
                   s.failed, rate.failures_per_s));
}

void caches(Viewer::Impl& v) {
  if (!ImGui::CollapsingHeader("Caches")) return;
  loader_lines("elevation", v.scene->elevation_loader(), v.elevation_rate);
  loader_lines("imagery", v.scene->imagery_loader(), v.imagery_rate);
  if (v.report) {
    const render::FrameStats& d = v.report->draw;
    text(fmt::format("GPU (L3): {} of {}, {} textures", format_bytes(d.gpu_bytes),
                     format_bytes(d.gpu_budget), d.gpu_textures));
  }
}

void frame_statistics(Viewer::Impl& v) {
  if (!ImGui::CollapsingHeader("Frame", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const std::vector<double> recent(v.recent_ms.begin(), v.recent_ms.end());
  const double p50 = view::percentile(recent, 0.5), p99 = view::percentile(recent, 0.99);
  text(fmt::format("{:.1f} fps; p50 {:.1f} ms, p99 {:.1f} ms ({} frames)",
                   p50 > 0 ? 1e3 / p50 : 0.0, p50, p99, recent.size()));
  if (!v.report) return;
  const view::FrameReport& r = *v.report;
  text(fmt::format("{} triangles ({:.2f}/px), {} quads, {} draw calls", r.draw.triangles,
                   r.draw.triangles_per_pixel(), r.selection.quads, r.draw.draw_calls));
  std::string levels = "quads per level:";
  for (size_t l = 0; l < r.selection.quads_per_level.size(); ++l) {
    if (r.selection.quads_per_level[l]) {
      levels += fmt::format(" {}:{}", l, r.selection.quads_per_level[l]);
    }
  }
  text(levels);
  text(fmt::format("uploaded {}, {}", format_bytes(r.draw.geometry_bytes + r.draw.texture_bytes),
                   r.complete ? "complete" : "loading"));
}

void cursor(Viewer::Impl& v) {
  if (!ImGui::CollapsingHeader("Cursor", ImGuiTreeNodeFlags_DefaultOpen)) return;
  if (!v.pick) {
    ImGui::TextDisabled(v.cursor_x < 0 ? "(outside the window)" : "(sky)");
    return;
  }
  const view::Pick& p = *v.pick;
  text(fmt::format("lon {:.5f}, lat {:.5f}", p.lon, p.lat));
  text(fmt::format("height {:.1f} m, distance {:.0f} m", p.height, p.distance));
}

void recorded_path(Viewer::Impl& v) {
  if (!ImGui::CollapsingHeader("Path")) return;
  bool recording = v.recording;
  if (ImGui::Checkbox("recording (F9)", &recording)) v.on_window_key(view::Key::f9);
  const double seconds = v.recorded.size() > 1 ? v.recorded.back().time - v.recorded[0].time : 0;
  text(fmt::format("{} keyframes, {:.1f} s", v.recorded.size(), seconds));
  if (ImGui::Button("export recorded path (F10)")) v.export_recorded();
  if (!v.export_status.empty()) text(v.export_status);
}

void load_progress(Viewer::Impl& v) {
  const LoadProgress& p = v.progress;
  const std::string label = p.pending == 0
                                ? std::string("loaded")
                                : fmt::format("{} of {} tiles", p.done, p.done + p.pending);
  ImGui::ProgressBar(p.fraction(), ImVec2(-1, 0), label.c_str());
}

}  // namespace

void draw_panels(Viewer::Impl& v) {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.8f);
  ImGui::Begin("relief", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  text(fmt::format("{} mode{}  (Tab: panels)", view::to_string(v.controller->mode()),
                   v.recording ? ", recording (F9)" : ""));
  load_progress(v);
  layers(v);
  texture_layer_panels(v);
  target_panel(v);
  level_of_detail(v);
  caches(v);
  frame_statistics(v);
  cursor(v);
  recorded_path(v);
  ImGui::End();
}

}  // namespace relief::window
