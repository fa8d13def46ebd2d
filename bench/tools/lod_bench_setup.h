#pragma once
// What bench/render and bench/refine-gl share: their command line
// (STORE pyrenees|himalaya [MARKDOWN_ROWS_OUT]), the store, a headless GL
// context and the fixed views of each view set.
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "relief/lod/camera.h"
#include "relief/render/terrain_renderer.h"
#include "relief/tiles/store.h"

namespace relief::bench {

struct ViewCase {
  const char* name;
  lod::Camera camera;
};

// pyrenees: the bundled SRTM pair; himalaya: the 4 x 6 degree SRTM3 block of
// ../shared/data/dem/srtm3-h44 (78-84 E, 28-32 N: plains of ~200 m in the
// south-west, the main range to 7 800 m across it). 1280 x 720.
inline std::vector<ViewCase> views_of(const std::string& set) {
  if (set == "pyrenees") {
    return {
        {"globe", {1.5, 30, 12e6, 0, -90, 0, 60, 1280, 720}},
        {"regional oblique", lod::look_at(1.5, 42.5, 1500, 60000, 20, -35, 60, 1280, 720)},
        {"low flight to the horizon", {1.05, 42.05, 2300, 35, -4, 0, 60, 1280, 720}},
    };
  }
  if (set == "himalaya") {
    return {
        {"globe", {81, 30, 12e6, 0, -90, 0, 60, 1280, 720}},
        {"regional oblique", lod::look_at(81, 30, 4000, 150000, 20, -35, 60, 1280, 720)},
        {"low flight to the horizon", {80.5, 28.55, 1200, 20, -3, 0, 60, 1280, 720}},
        {"straight down from 900 km", {81, 30, 900e3, 0, -90, 0, 60, 1280, 720}},
    };
  }
  return {};
}

struct LodBench {
  std::string view_set;
  std::vector<ViewCase> views;
  FILE* markdown = nullptr;  // rows appended, when asked
  std::optional<tiles::Store> store;
  std::unique_ptr<render::GlContext> context;
};

// Parses the command line and opens what it names; on failure prints why and
// sets `exit_code` (2: usage, 1: anything else).
inline std::optional<LodBench> open_lod_bench(int argc, char** argv, const char* tool,
                                              int& exit_code) {
  exit_code = 2;
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: %s STORE pyrenees|himalaya [MARKDOWN_ROWS_OUT]\n", tool);
    return std::nullopt;
  }
  LodBench b;
  b.view_set = argv[2];
  b.views = views_of(b.view_set);
  if (b.views.empty()) {
    std::fprintf(stderr, "%s: unknown view set (pyrenees, himalaya)\n", argv[2]);
    return std::nullopt;
  }
  exit_code = 1;
  b.markdown = argc == 4 ? std::fopen(argv[3], "a") : nullptr;
  if (argc == 4 && !b.markdown) {
    std::fprintf(stderr, "%s: cannot open for appending\n", argv[3]);
    return std::nullopt;
  }
  auto store = tiles::Store::open(argv[1]);
  if (!store) {
    std::fprintf(stderr, "%s\n", store.error().message.c_str());
    return std::nullopt;
  }
  b.store.emplace(std::move(*store));
  auto context = render::GlContext::create_headless();
  if (!context) {
    std::fprintf(stderr, "%s\n", context.error().message.c_str());
    return std::nullopt;
  }
  b.context = std::move(*context);
  exit_code = 0;
  return b;
}

// Closes the markdown file; false (and a message) when its writes failed.
inline bool close_markdown(LodBench& b, const char* path) {
  if (b.markdown && std::fclose(b.markdown) != 0) {
    std::fprintf(stderr, "%s: write failed\n", path);
    return false;
  }
  b.markdown = nullptr;
  return true;
}

}  // namespace relief::bench
