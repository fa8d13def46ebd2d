#include <cstdio>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "args.h"
#include "commands.h"
#include "open_store.h"
#include "relief/base/file_io.h"
#include "relief/base/units.h"
#include "relief/lod/selection.h"
#include "relief/render/terrain_renderer.h"
#include "relief/tiles/codec.h"

namespace relief::cli {

namespace {
constexpr const char* kHelp =
    R"(usage: relief render STORE [--imagery STORE2] (--camera C | --look-at L) -o FRAME.png [options]

Renders one complete frame of an elevation store, headless (EGL; Mesa's
llvmpipe where there is no GPU): every quad the view needs at the chosen level
of detail is loaded before drawing. Quads are split while their mesh error,
projected at their nearest point, exceeds --pixel-error pixels.

  --camera LON,LAT,HEIGHT,HEADING,PITCH,ROLL
                     eye position (degrees, metres above the WGS84 ellipsoid) and
                     orientation (degrees: heading clockwise from north, pitch < 0 looks down)
  --look-at LON,LAT,HEIGHT,RANGE,HEADING,PITCH
                     look at a point from RANGE metres away
options:
  -o, --output FILE  PNG to write (atomically)
  --imagery STORE2   drape an imagery store; otherwise hypsometric colours with hillshade
  --size WxH         image size in pixels (default 1024x768)
  --fov DEG          vertical field of view (default 60)
  --pixel-error E    largest screen-space error in pixels (default 1)
  --exaggeration X   vertical exaggeration (default 1)
  --mesh-level R     mesh refinement per quad: 2^(R+1) x 2^R squares (default 4)
  --full-resolution  every finest sample a vertex (the brute-force reference)
  --sky R,G,B        background colour, 0-255 (default 156,189,224)
  --stats FILE       per-frame statistics as JSON
  --cache DIR        for a store given as http:// URL(s): keep fetched files under DIR
  --cache-size SIZE  budget of that disk cache (default 1GiB)
)";

Result<tiles::Store> open_kind(const std::string& path, tiles::DatasetKind kind, const char* role,
                               const std::string& cache_dir = "", uint64_t cache_bytes = 0) {
  tiles::Store s = RELIEF_TRY(open_store(path, cache_dir, cache_bytes));
  if (s.manifest().kind != kind) {
    return fail(fmt::format("{}: holds {} data; {} must be an {} store", path,
                            tiles::to_string(s.manifest().kind), role, tiles::to_string(kind)));
  }
  return s;
}

nlohmann::json stats_json(const lod::Selection& s, const render::FrameStats& f) {
  nlohmann::json levels = nlohmann::json::object();
  for (size_t l = 0; l < s.stats.quads_per_level.size(); ++l) {
    if (s.stats.quads_per_level[l]) levels[std::to_string(l)] = s.stats.quads_per_level[l];
  }
  return {{"quads", s.stats.quads},
          {"quads_per_level", levels},
          {"triangles", f.triangles},
          {"draw_calls", f.draw_calls},
          {"culled_quads", s.stats.culled},
          {"selection_ms", s.stats.seconds * 1e3},
          {"prepare_ms", f.prepare_seconds * 1e3},
          {"gpu_ms", f.gpu_seconds * 1e3},
          {"max_error_pixels", s.stats.max_error_pixels}};
}

}  // namespace

int run_render(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kHelp);
  auto args = Args::parse(argv,
                          {{"--output", "-o"},
                           {"--imagery"},
                           {"--camera"},
                           {"--look-at"},
                           {"--size"},
                           {"--fov"},
                           {"--pixel-error"},
                           {"--exaggeration"},
                           {"--mesh-level"},
                           {"--full-resolution", "", false},
                           {"--sky"},
                           {"--stats"},
                           {"--cache"},
                           {"--cache-size"}},
                          "render");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("render: expected exactly one STORE");
  if (!args->get("--output")) return report_error("render: -o FRAME.png is required");
  if (!args->get("--camera") == !args->get("--look-at")) {
    return report_error("render: give exactly one of --camera and --look-at");
  }
  int width = 1024, height = 768;
  if (auto s = args->get("--size")) {
    char x = 0, end = 0;
    if (std::sscanf(s->c_str(), "%d%c%d%c", &width, &x, &height, &end) != 3 || x != 'x' ||
        width < 1 || height < 1 || width > 16384 || height > 16384) {
      return report_error("--size: '" + *s + "' is not WxH between 1x1 and 16384x16384");
    }
  }
  double fov = 60, pixel_error = 1, exaggeration = 1;
  for (auto [name, target, lo, hi] : {std::tuple{"--fov", &fov, 1.0, 170.0},
                                      std::tuple{"--pixel-error", &pixel_error, 0.05, 1000.0},
                                      std::tuple{"--exaggeration", &exaggeration, 0.0, 100.0}}) {
    auto v = args->get_double(name);
    if (!v) return report_error(v.error().message);
    if (*v) {
      if (!(**v >= lo && **v <= hi))
        return report_error(fmt::format("{}: must be in [{}, {}]", name, lo, hi));
      *target = **v;
    }
  }
  auto mesh_level = args->get_int("--mesh-level", 0, 8);
  if (!mesh_level) return report_error(mesh_level.error().message);
  std::array<float, 3> sky = render::RenderOptions{}.sky;
  if (auto s = args->get("--sky")) {
    auto c = parse_numbers("--sky", *s, 3);
    if (!c) return report_error(c.error().message);
    for (int i = 0; i < 3; ++i) sky[i] = static_cast<float>(std::clamp((*c)[i], 0.0, 255.0) / 255);
  }

  uint64_t cache_bytes = uint64_t{1} << 30;
  if (auto size = args->get("--cache-size")) {
    auto bytes = parse_byte_size(*size);
    if (!bytes) return report_error("--cache-size: " + bytes.error().message);
    cache_bytes = *bytes;
  }
  const std::string cache_dir = args->get("--cache").value_or("");
  auto store = open_kind(args->positional()[0], tiles::DatasetKind::Elevation, "STORE", cache_dir,
                         cache_bytes);
  if (!store) return report_error(store.error().message);
  std::optional<tiles::Store> imagery;
  if (auto path = args->get("--imagery")) {
    auto s = open_kind(*path, tiles::DatasetKind::Imagery, "--imagery");
    if (!s) return report_error(s.error().message);
    imagery = std::move(*s);
  }
  lod::Camera camera;
  if (auto c = args->get("--camera")) {
    auto v = parse_numbers("--camera", *c, 6);
    if (!v) return report_error(v.error().message);
    camera = {(*v)[0], (*v)[1], (*v)[2], (*v)[3], (*v)[4], (*v)[5], fov, width, height};
  } else {
    auto v = parse_numbers("--look-at", *args->get("--look-at"), 6);
    if (!v) return report_error(v.error().message);
    if (!((*v)[3] > 0)) return report_error("--look-at: the range must be > 0");
    camera = lod::look_at((*v)[0], (*v)[1], (*v)[2], (*v)[3], (*v)[4], (*v)[5], fov, width, height);
  }
  auto view = lod::make_view(camera);
  if (!view) return report_error(view.error().message);
  // Below the ground: the terrain under the eye, at the finest level.
  auto ground = store->sample(camera.lon, camera.lat, store->manifest().max_level);
  if (!ground) return report_error(ground.error().message);
  if (*ground && camera.height < **ground) {
    return report_error(fmt::format("--camera: {:.1f} m is below the ground ({:.1f} m) at {},{}",
                                    camera.height, **ground, camera.lon, camera.lat));
  }

  // The brute-force reference: one vertex per finest sample, no deeper quads.
  const int full_level = static_cast<int>(std::log2(store->grid().height()));
  const lod::MeshTopology mesh(args->has("--full-resolution") ? full_level
                                                              : mesh_level->value_or(4));
  lod::TerrainModel terrain(&*store, mesh, uint64_t{512} << 20);
  lod::SelectionOptions so;
  so.pixel_error = pixel_error;
  so.full_resolution = args->has("--full-resolution");
  if (imagery) so.texture_max_level = imagery->manifest().max_level;
  auto selection = lod::select_quads(*view, terrain, so);
  if (!selection) return report_error(selection.error().message);

  auto context = render::GlContext::create_headless();
  if (!context) return report_error(context.error().message);
  auto target = render::make_offscreen_target(width, height);
  if (!target) return report_error(target.error().message);
  auto renderer = render::TerrainRenderer::create(terrain, imagery ? &*imagery : nullptr);
  if (!renderer) return report_error(renderer.error().message);
  render::RenderOptions ro;
  ro.exaggeration = static_cast<float>(exaggeration);
  ro.sky = sky;
  auto frame = (*renderer)->draw(*view, *selection, **target, ro);
  if (!frame) return report_error(frame.error().message);
  auto pixels = (*target)->read_rgba();
  if (!pixels) return report_error(pixels.error().message);
  tiles::Raster image(tiles::SampleType::UInt8, 4, width, height);
  std::copy(pixels->begin(), pixels->end(), image.u8().begin());
  auto png = tiles::encode(image, tiles::CodecOptions{tiles::Codec::Png});
  if (!png) return report_error(png.error().message);
  const std::string out = *args->get("--output");
  if (auto st = write_file_atomic(out, *png); !st) return report_error(st.error().message);
  if (auto path = args->get("--stats")) {
    const std::string text = stats_json(*selection, *frame).dump(1);
    if (auto st = write_file_atomic(*path, std::as_bytes(std::span(text.data(), text.size())));
        !st) {
      return report_error(st.error().message);
    }
  }
  std::printf("wrote %s: %dx%d, %u quads, %llu triangles, selection %.2f ms, gpu %.1f ms\n",
              out.c_str(), width, height, selection->stats.quads,
              static_cast<unsigned long long>(frame->triangles), selection->stats.seconds * 1e3,
              frame->gpu_seconds * 1e3);
  return 0;
}

}  // namespace relief::cli
