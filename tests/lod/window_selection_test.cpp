// A view with a window (a sort-first rank's part, one display of a wall)
// selects only what its window shows, with the whole view's error metric:
// fewer quads, each meeting the window's frustum, every part of the window
// still covered, and the same pixel-error bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "../ingest/built_stores.h"
#include "relief/lod/selection.h"

namespace relief::lod {
namespace {

bool covered(const std::set<geo::TileKey>& keys, const geo::TileKey& key) {
  for (geo::TileKey k = key;; k = *k.parent()) {  // the key or an ancestor
    if (keys.count(k)) return true;
    if (k.level == 0) break;
  }
  // or descendants
  return std::any_of(keys.begin(), keys.end(), [&](const geo::TileKey& k) {
    return k.level > key.level && (k.x >> (k.level - key.level)) == key.x &&
           (k.y >> (k.level - key.level)) == key.y;
  });
}

TEST(WindowSelection, AWindowSelectsOnlyWhatItShowsWithTheWholeViewsErrors) {
  const tiles::Store& store = relief::testing::pyrenees_store();
  const MeshTopology mesh(4);
  TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  auto whole = make_view(look_at(1.45, 42.55, 1500, 40000, 20, -35, 60, 640, 480));
  ASSERT_TRUE(whole);
  SelectionOptions o;
  o.pixel_error = 1.0;
  auto all = select_quads(*whole, terrain, o);
  ASSERT_TRUE(all) << all.error().message;
  for (const PixelRect& rect : {PixelRect{0, 0, 320, 480}, PixelRect{320, 0, 320, 480},
                                PixelRect{0, 240, 640, 240}, PixelRect{100, 100, 200, 150}}) {
    SCOPED_TRACE(::testing::Message()
                 << rect.x << "," << rect.y << " " << rect.width << "x" << rect.height);
    auto view = with_window(*whole, rect);
    ASSERT_TRUE(view);
    auto part = select_quads(*view, terrain, o);
    ASSERT_TRUE(part) << part.error().message;
    EXPECT_LT(part->quads.size(), all->quads.size());
    EXPECT_LE(part->stats.max_error_pixels, o.pixel_error);
    const std::array<Plane, 5> planes = window_planes(*view);
    std::set<geo::TileKey> keys;
    for (const SelectedQuad& q : part->quads) {
      keys.insert(q.key);
      auto info = terrain.quad(q.key);
      ASSERT_TRUE(info);
      EXPECT_FALSE(outside(planes, (*info)->box.lo, (*info)->box.hi)) << q.key.to_string();
    }
    // Whatever the whole view draws inside the window, the window draws too.
    for (const SelectedQuad& q : all->quads) {
      auto info = terrain.quad(q.key);
      ASSERT_TRUE(info);
      if (outside(planes, (*info)->box.lo, (*info)->box.hi)) continue;
      EXPECT_TRUE(covered(keys, q.key)) << q.key.to_string();
    }
  }
}

}  // namespace
}  // namespace relief::lod
