#include "layer_panels.h"

#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <imgui.h>

namespace relief::window {
namespace {

// One parameter as a slider over its valid range: integers as integers,
// wide positive ranges logarithmic. Returns true when it changed.
bool parameter_slider(const process::ParamSpec& spec, double& value) {
  const std::string label = spec.name;
  if (spec.integer) {
    int v = static_cast<int>(std::lround(value));
    const int hi = static_cast<int>(std::min(spec.max, spec.min + 64.0));
    if (!ImGui::SliderInt(label.c_str(), &v, static_cast<int>(spec.min), hi)) return false;
    value = v;
    return true;
  }
  float v = static_cast<float>(value);
  const bool wide = spec.min > 0 && spec.max / spec.min > 100;
  if (!ImGui::SliderFloat(label.c_str(), &v, static_cast<float>(spec.min),
                          static_cast<float>(spec.max), "%.4g",
                          wide ? ImGuiSliderFlags_Logarithmic : ImGuiSliderFlags_None)) {
    return false;
  }
  value = v;
  return true;
}

bool chain_sliders(gpuprocess::OperatorChain& chain) {
  bool changed = false;
  for (size_t s = 0; s < chain.steps.size(); ++s) {
    gpuprocess::ChainStep& step = chain.steps[s];
    ImGui::PushID(static_cast<int>(s));
    ImGui::TextUnformatted(step.op->name.c_str());
    for (const process::ParamSpec& spec : step.op->params) {
      auto it = step.params.find(spec.name);
      if (it == step.params.end() || std::isnan(it->second)) continue;  // derived from statistics
      changed |= parameter_slider(spec, it->second);
    }
    ImGui::PopID();
  }
  return changed;
}

bool layer_controls(render::TextureLayer& l) {
  bool changed = ImGui::SliderFloat("opacity", &l.opacity, 0.0f, 1.0f, "%.2f");
  if (l.store->manifest().sample_type == tiles::SampleType::UInt8) return changed;  // RGBA
  float range[2] = {l.range_min, l.range_max};
  const float speed = std::max(1e-4f, (l.range_max - l.range_min) / 200);
  if (ImGui::DragFloat2("range", range, speed) && range[0] < range[1]) {
    l.range_min = range[0], l.range_max = range[1];
    changed = true;
  }
  int map = l.colormap == gpuprocess::ColorMap::viridis ? 1 : 0;
  if (ImGui::Combo("colour map", &map, "grey\0viridis\0")) {
    l.colormap = map ? gpuprocess::ColorMap::viridis : gpuprocess::ColorMap::grey;
    changed = true;
  }
  changed |= chain_sliders(l.chain);
  for (size_t k = 0; k < l.lenses.size(); ++k) {
    render::Lens& lens = l.lenses[k];
    ImGui::PushID(static_cast<int>(100 + k));
    ImGui::TextUnformatted(fmt::format("lens {} (drag it on the terrain)", k).c_str());
    double centre[2] = {lens.lon, lens.lat};
    if (ImGui::InputScalarN("lon, lat", ImGuiDataType_Double, centre, 2, nullptr, nullptr, "%.5f",
                            ImGuiInputTextFlags_EnterReturnsTrue) &&
        std::isfinite(centre[0]) && std::abs(centre[1]) <= 90) {
      lens.lon = centre[0] - 360 * std::round(centre[0] / 360);
      lens.lat = centre[1];
      changed = true;
    }
    float radius = static_cast<float>(lens.radius_m);
    if (ImGui::SliderFloat("radius m", &radius, 1.0f, 100000.0f, "%.0f",
                           ImGuiSliderFlags_Logarithmic)) {
      lens.radius_m = radius;
      changed = true;
    }
    changed |= chain_sliders(lens.chain);
    ImGui::PopID();
  }
  return changed;
}

}  // namespace

void texture_layer_panels(Viewer::Impl& v) {
  std::vector<render::TextureLayer>& layers = v.scene_options.texture_layers;
  if (layers.empty()) return;
  if (!ImGui::CollapsingHeader("Texture layers", ImGuiTreeNodeFlags_DefaultOpen)) return;
  bool changed = false;
  for (size_t i = 0; i < layers.size(); ++i) {
    ImGui::PushID(static_cast<int>(i));
    ImGui::TextUnformatted(
        fmt::format("{}: {}", i, layers[i].store->root().filename().string()).c_str());
    changed |= layer_controls(layers[i]);
    ImGui::Separator();
    ImGui::PopID();
  }
  if (changed) {
    // Parameters the scene refuses (a radius wider than the tiles' border)
    // are taken back and said in the panel.
    if (auto st = v.scene->set_texture_layers(layers); !st) {
      v.layer_error = st.error().message;
      layers = v.scene->options().texture_layers;
    } else {
      v.layer_error.clear();
    }
  }
  if (!v.layer_error.empty()) {
    ImGui::PushTextWrapPos(420);
    ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", v.layer_error.c_str());
    ImGui::PopTextWrapPos();
  }
}

void target_panel(Viewer::Impl& v) {
  view::TargetHints* hints = v.scene->target_hints();
  if (!hints) return;
  if (!ImGui::CollapsingHeader("Targets", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const std::vector<view::TargetHint>& shown = v.scene->last_hints();
  ImGui::TextUnformatted(fmt::format("{} hints drawn", shown.size()).c_str());
  // The hint nearest the cursor, within its circle.
  const view::TargetHint* near = nullptr;
  if (v.drawn_camera && v.cursor_x >= 0) {
    if (auto view = lod::make_view(*v.drawn_camera)) {
      double best = 12 * 12;
      for (const view::TargetHint& h : shown) {
        double x = 0, y = 0;
        const double height = v.pick ? v.pick->height : 0;
        if (!view->project(lod::ecef(h.lon, h.lat, height), x, y)) continue;
        const double d2 = (x - v.cursor_x) * (x - v.cursor_x) + (y - v.cursor_y) * (y - v.cursor_y);
        if (d2 < best) best = d2, near = &h;
      }
    }
  }
  if (!near) {
    ImGui::TextDisabled("(point at a hint for its analysis)");
    return;
  }
  const auto key = std::pair{near->detection.x, near->detection.y};
  if (!v.analysis || v.analysed != key) {
    auto a = hints->analyse(*near, 32);
    v.analysed = key;
    v.analysis.reset();
    if (!a) {
      ImGui::TextUnformatted(a.error().message.c_str());
      return;
    }
    v.analysis = *a;
  }
  const process::TargetAnalysis& a = *v.analysis;
  ImGui::TextUnformatted(
      fmt::format("target at {:.5f}, {:.5f}, amplitude {:.1f}", near->lon, near->lat, a.amplitude)
          .c_str());
  ImGui::TextUnformatted(fmt::format("PSLR {:.1f} dB", a.pslr_db).c_str());
  for (int axis = 0; axis < 2; ++axis) {
    const process::CrossSection& c = a.axes[axis];
    std::vector<float> db;
    for (double d : c.db) db.push_back(std::isnan(d) ? -60.0f : static_cast<float>(d));
    const std::string label = fmt::format("axis {:.0f} deg: PSLR {:.1f} dB, -3 dB width {:.2f}",
                                          c.direction, c.pslr_db, c.width_3db);
    ImGui::TextUnformatted(label.c_str());
    ImGui::PushID(axis);
    ImGui::PlotLines("dB", db.data(), static_cast<int>(db.size()), 0, nullptr, -60.0f, 0.0f,
                     ImVec2(300, 60));
    ImGui::PopID();
  }
}

}  // namespace relief::window
