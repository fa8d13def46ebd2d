// The exact quad errors a non-blocking provider's threads measure as tiles
// decode (TerrainModel::prepare_errors_on_load), and their absence once an
// edge-mark scene, whose selection never asks for them, skips them.
#include <gtest/gtest.h>

#include "../ingest/built_stores.h"
#include "relief/lod/mesh_topology.h"
#include "relief/lod/terrain_model.h"

namespace relief::lod {
namespace {

// Never waits: decodes on demand and runs the prepare hook as the loader's
// threads would before the tile becomes resident (here on the caller's).
class DecodingProvider : public TileProvider {
 public:
  explicit DecodingProvider(const tiles::Store& store) : store_(store) {}
  bool blocking() const override { return false; }
  Result<TilePtr> get(const geo::TileKey& key) override {
    TilePtr t = RELIEF_TRY(decode_heights(store_, key));
    if (prepare_) prepare_(key, *t);
    return t;
  }
  void set_prepare(Prepare prepare) override { prepare_ = std::move(prepare); }

 private:
  const tiles::Store& store_;
  Prepare prepare_;
};

TEST(ExactErrorsOnLoad, MeasuredByTheLoaderUnlessSkipped) {
  const tiles::Store& store = relief::testing::pyrenees_store();
  const MeshTopology mesh(4);
  const geo::TileKey key = store.index(store.manifest().max_level).entries().front().key;
  for (const bool skip : {false, true}) {
    SCOPED_TRACE(skip ? "skipped" : "on load");
    DecodingProvider provider(store);
    TerrainModel terrain(store, mesh, provider);
    if (skip) terrain.skip_exact_errors_on_load();
    terrain.begin_frame();
    ASSERT_TRUE(terrain.available(key));
    ASSERT_TRUE(terrain.available(*key.parent()));
    auto info = terrain.quad(key);
    ASSERT_TRUE(info) << info.error().message;
    auto error = terrain.quad_error(key, **info);
    ASSERT_TRUE(error) << error.error().message;
    EXPECT_GT(*error, 0);
    EXPECT_EQ(terrain.error_counts().prepared, skip ? 0u : 1u);
    EXPECT_EQ(terrain.error_counts().measured, skip ? 1u : 0u);
    terrain.end_frame();
  }
}

}  // namespace
}  // namespace relief::lod
