#pragma once
// The terrains, selections and views the refinement tests share
// (refine_test.cpp, refine_lanes_test.cpp): the Pyrenees pair and the Scotland
// pair (55N, west of Greenwich), each with its own diamond-error cache.
#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "../ingest/built_stores.h"
#include "../support/test_support.h"
#include "relief/lod/refine.h"

namespace relief::lod::testing {

inline const tiles::Store& scotland_store() {
  ingest::BuildOptions o;
  o.inputs = {relief::testing::data("srtm/N55W004.hgt.zip"),
              relief::testing::data("srtm/N55W003.hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  return relief::testing::built_store("scotland", o);
}

struct Terrain {
  explicit Terrain(const tiles::Store& s) : store(s), terrain(&s, mesh, uint64_t{512} << 20) {}
  const tiles::Store& store;
  MeshTopology mesh{4};
  TerrainModel terrain;
  RefineCache cache{uint64_t{1} << 30};
};

inline Terrain& pyrenees() {
  static Terrain t(relief::testing::pyrenees_store());
  return t;
}
inline Terrain& scotland() {
  static Terrain t(scotland_store());
  return t;
}

// The quad selection refinement starts from (LodMode::edge_marks): capped at
// the store's finest level, and with level errors, which refinement cannot
// reduce, projecting to at most `level_error_share` of `pixel_error`.
inline Selection select(Terrain& t, const View& view, double pixel_error,
                        double level_error_share = 0.5, int max_level = -1,
                        std::function<bool(const geo::TileKey&)> also_split = {}) {
  SelectionOptions o;
  o.also_split = std::move(also_split);
  o.max_level = max_level;
  o.pixel_error = pixel_error;
  o.mode = LodMode::edge_marks;
  o.level_error_share = level_error_share;
  o.neighbour_indices = true;
  auto s = select_quads(view, t.terrain, o);
  EXPECT_TRUE(s) << s.error().message;
  return s ? std::move(*s) : Selection{};
}

inline RefinedMesh refined(Terrain& t, const View& view, const Selection& s, double pixel_error,
                           RefineVariant variant) {
  RefineOptions o;
  o.pixel_error = pixel_error;
  o.variant = variant;
  o.cache = &t.cache;
  auto mesh = refine(view, t.terrain, s, o);
  EXPECT_TRUE(mesh) << mesh.error().message;
  return mesh ? std::move(*mesh) : RefinedMesh{};
}

struct Case {
  const char* name;
  Terrain& (*terrain)();
  Camera camera;
  double pixel_error;
};

// The views of error_bound_test, a grazing one, and one at 55N west of Greenwich.
inline std::vector<Case> cases() {
  return {
      {"oblique", pyrenees, look_at(1.45, 42.55, 1500, 30000, 20, -35, 60, 640, 480), 1.0},
      {"low", pyrenees, look_at(1.6, 42.4, 1200, 15000, 200, -15, 60, 640, 480), 1.0},
      {"down", pyrenees, look_at(1.5, 42.6, 2000, 60000, 0, -80, 45, 512, 512), 2.0},
      {"grazing", pyrenees, look_at(1.3, 42.45, 1500, 8000, 100, -4, 60, 640, 480), 1.0},
      {"scotland", scotland, look_at(-3.2, 55.5, 300, 20000, 300, -30, 60, 640, 480), 1.0},
  };
}

inline const Case& case_named(const std::string& name) {
  static const std::vector<Case> all = cases();
  for (const Case& c : all) {
    if (name == c.name) return c;
  }
  throw std::runtime_error("no case " + name);
}

}  // namespace relief::lod::testing
