#include "texture_options.h"

#include <algorithm>
#include <optional>

#include <fmt/format.h>

#include "args.h"
#include "open_store.h"

namespace relief::cli {

const char* const kTextureOptionsHelp =
    R"(texture layers (repeat per layer, bottom first; docs/gpu-processing.md):
  --texture STORE    drape a store: RGBA imagery as it is, a single-band store
                     (SAR, elevation) through its operators and a colour map
  --texture-op OP    an operator of `relief process --list`, run on the GPU at
                     draw time; repeat for a chain, applied in the order given
  --texture-param K=V  a parameter of the --texture-op before it (the finest
                     level's; coarser levels scale masks to the same ground size)
  --texture-range MIN,MAX  values mapped to the colour map's ends
                     (default: the store's min and max, SAR up to mean + 3 std;
                     [0, 1] after a dynamic-range mapping)
  --texture-opacity A  in [0, 1] (default 1)
  --texture-colormap NAME  grey (default) or viridis
  --lens LON,LAT,RADIUS_M  a lens over the --texture before it: inside the circle
                     its samples go through the --lens-op chain instead
  --lens-op OP, --lens-param K=V  the lens's chain (as --texture-op, --texture-param)
  --process-on WHERE  gpu, cpu or auto (default): where the layers' operators
                     run; cpu: the CPU kernels on worker threads, the result
                     mapped and composited on the GPU; auto: cpu on a software
                     renderer (llvmpipe), gpu otherwise
  --detect           point-target hints over the first SAR layer: a circle, the
                     side-lobe axes and a PSLR bar per target (docs/target-hints.md)
  --detect-level F, --detect-sensitivity T  as relief detect's --level (default
                     0.15 of the maximum) and --sensitivity (default 1.5)
)";

Result<gpuprocess::OperatorChain> make_chain(const char* option, const OperatorTexts& ops) {
  gpuprocess::OperatorChain chain;
  for (const auto& [op, params] : ops) {
    auto step = gpuprocess::make_step(op, params);
    if (!step) return fail(fmt::format("{} {}: {}", option, op, step.error().message));
    chain.steps.push_back(std::move(*step));
  }
  return chain;
}

Result<LensCircle> parse_lens_circle(const char* option, const std::string& text) {
  auto v = RELIEF_TRY(parse_numbers(option, text, 3));
  if (!(v[0] >= -180 && v[0] < 360) || !(v[1] >= -90 && v[1] <= 90)) {
    return fail(fmt::format("{}: {},{} is not a longitude, latitude", option, v[0], v[1]));
  }
  if (!(v[2] > 0)) return fail(fmt::format("{}: radius {} m must be > 0", option, v[2]));
  return LensCircle{v[0] > 180 ? v[0] - 360 : v[0], v[1], v[2]};
}

namespace {

using Ops = OperatorTexts;

struct LensText {
  std::string where;
  Ops ops;
};

struct LayerText {
  std::string store;
  Ops ops;
  std::optional<std::string> range, opacity, colormap;
  std::vector<LensText> lenses;
};

Result<render::Lens> make_lens(const LensText& t) {
  const LensCircle c = RELIEF_TRY(parse_lens_circle("--lens", t.where));
  render::Lens lens;
  lens.lon = c.lon, lens.lat = c.lat, lens.radius_m = c.radius_m;
  lens.chain = RELIEF_TRY(make_chain("--lens-op", t.ops));
  return lens;
}

Result<render::TextureLayer> make_layer(const LayerText& t, const tiles::Store& store) {
  render::TextureLayer l;
  l.store = &store;
  l.chain = RELIEF_TRY(make_chain("--texture-op", t.ops));
  for (const LensText& lens : t.lenses) l.lenses.push_back(RELIEF_TRY(make_lens(lens)));
  const tiles::SampleStats& st = store.manifest().stats;
  // SAR amplitudes have a long tail: up to mean + 3 std, as the linear mapping.
  const double top = store.manifest().kind == tiles::DatasetKind::Sar
                         ? std::min(st.max, st.mean + 3 * st.stddev)
                         : st.max;
  l.range_min = static_cast<float>(st.min), l.range_max = static_cast<float>(top);
  if (!l.chain.steps.empty() && l.chain.steps.back().op->needs_global_stats) {
    l.range_min = 0, l.range_max = 1;  // dynamic-range mappings give [0, 1]
  }
  if (t.range) {
    auto v = RELIEF_TRY(parse_numbers("--texture-range", *t.range, 2));
    if (!(v[0] < v[1])) {
      return fail(fmt::format("--texture-range: MIN ({}) must be less than MAX ({})", v[0], v[1]));
    }
    l.range_min = static_cast<float>(v[0]), l.range_max = static_cast<float>(v[1]);
  }
  if (t.opacity) {
    auto v = RELIEF_TRY(parse_numbers("--texture-opacity", *t.opacity, 1));
    if (!(v[0] >= 0 && v[0] <= 1)) {
      return fail(fmt::format("--texture-opacity: {} is not in [0, 1]", v[0]));
    }
    l.opacity = static_cast<float>(v[0]);
  }
  if (t.colormap) {
    auto map = gpuprocess::parse_colormap(*t.colormap);
    if (!map) return fail("--texture-colormap: " + map.error().message);
    l.colormap = *map;
  }
  if (store.manifest().sample_type != tiles::SampleType::Float32 && (t.range || t.colormap)) {
    return fail(
        fmt::format("{}: --texture-range and --texture-colormap are for single-band "
                    "stores, not RGBA imagery",
                    t.store));
  }
  RELIEF_CHECK(render::check_texture_layer(l));
  return l;
}

}  // namespace

Result<TextureLayers> take_texture_layers(std::vector<std::string>& argv) {
  std::vector<std::string> rest;
  std::vector<LayerText> texts;
  std::optional<render::ProcessOn> process_on;
  for (size_t i = 0; i < argv.size(); ++i) {
    std::string name = argv[i], value;
    if (!name.starts_with("--texture") && !name.starts_with("--lens") &&
        !name.starts_with("--process-on")) {
      rest.push_back(argv[i]);
      continue;
    }
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1), name = name.substr(0, eq);
    } else if (i + 1 < argv.size()) {
      value = argv[++i];
    } else {
      return fail(fmt::format("option {} needs a value", name));
    }
    if (name == "--texture") {
      texts.push_back({value, {}, {}, {}, {}, {}});
      continue;
    }
    if (name == "--process-on") {
      auto where = render::parse_process_on(value);
      if (!where) return fail("--process-on: " + where.error().message);
      process_on = *where;
      continue;
    }
    if (texts.empty()) return fail(fmt::format("{} {}: comes before any --texture", name, value));
    LayerText& t = texts.back();
    if (name == "--texture-op") {
      t.ops.push_back({value, {}});
    } else if (name == "--texture-param") {
      if (t.ops.empty()) {
        return fail(fmt::format("--texture-param {}: comes before any --texture-op", value));
      }
      t.ops.back().second.push_back(value);
    } else if (name == "--lens") {
      t.lenses.push_back({value, {}});
    } else if (name == "--lens-op") {
      if (t.lenses.empty())
        return fail(fmt::format("--lens-op {}: comes before any --lens", value));
      t.lenses.back().ops.push_back({value, {}});
    } else if (name == "--lens-param") {
      if (t.lenses.empty() || t.lenses.back().ops.empty()) {
        return fail(fmt::format("--lens-param {}: comes before any --lens-op", value));
      }
      t.lenses.back().ops.back().second.push_back(value);
    } else if (name == "--texture-range") {
      t.range = value;
    } else if (name == "--texture-opacity") {
      t.opacity = value;
    } else if (name == "--texture-colormap") {
      t.colormap = value;
    } else {
      return fail(fmt::format("unknown option '{}'", name));
    }
  }
  if (process_on && texts.empty()) {
    return fail("--process-on: there is no --texture layer to process");
  }
  argv = std::move(rest);
  TextureLayers out;
  for (const LayerText& t : texts) {
    out.stores.push_back(RELIEF_TRY(open_store(t.store)));
    out.paths.push_back(t.store);
    out.layers.push_back(RELIEF_TRY(make_layer(t, out.stores.back())));
    if (process_on) out.layers.back().process_on = *process_on;
  }
  return out;
}

}  // namespace relief::cli
