// libs/parallel without MPI: screen tiles, quad decompositions, walls,
// the compositing rule and the views' windows.
#include <gtest/gtest.h>

#include <numeric>
#include <random>

#include "relief/lod/camera.h"
#include "relief/parallel/composite.h"
#include "relief/parallel/decompose.h"
#include "relief/parallel/wall.h"

namespace relief::parallel {
namespace {

TEST(ScreenTiles, CoverTheViewExactlyOnce) {
  for (ScreenSplit split : {ScreenSplit::horizontal, ScreenSplit::vertical, ScreenSplit::grid}) {
    for (int ranks = 1; ranks <= 7; ++ranks) {
      const auto tiles = screen_tiles(321, 239, split, ranks);
      ASSERT_EQ(tiles.size(), size_t(ranks));
      std::vector<int> covered(321 * 239, 0);
      for (const lod::PixelRect& t : tiles) {
        for (int y = t.y; y < t.y + t.height; ++y) {
          for (int x = t.x; x < t.x + t.width; ++x) ++covered[y * 321 + x];
        }
      }
      EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }));
    }
  }
  // Four ranks on a wide view: a 2 x 2 grid; strips otherwise.
  EXPECT_EQ(screen_tiles(320, 240, ScreenSplit::grid, 4)[3], (lod::PixelRect{160, 120, 160, 120}));
  EXPECT_EQ(screen_tiles(320, 240, ScreenSplit::horizontal, 2)[1],
            (lod::PixelRect{0, 120, 320, 120}));
  EXPECT_EQ(screen_tiles(320, 240, ScreenSplit::vertical, 2)[1],
            (lod::PixelRect{160, 0, 160, 240}));
}

TEST(ParallelMode, ParsesTheModesAndRejectsOthers) {
  EXPECT_EQ(parse_parallel_mode("sort-first:grid")->screen, ScreenSplit::grid);
  EXPECT_EQ(parse_parallel_mode("sort-last:quadtree")->quads, QuadSplit::quadtree);
  EXPECT_EQ(parse_parallel_mode("wall:a.json")->wall_file, "a.json");
  for (const char* bad : {"", "sort-first", "sort-first:x", "sort-last:", "wall:", "sort-middle"}) {
    auto m = parse_parallel_mode(bad);
    ASSERT_FALSE(m) << bad;
    EXPECT_NE(m.error().message.find("--parallel"), std::string::npos);
  }
}

// A front of quads of levels 13 and 14 over a one-degree extent, the western half
// twice as fine (four times the quads).
struct Front {
  std::vector<geo::TileKey> keys;
  std::vector<uint64_t> triangles;
};
Front uneven_front(const geo::GeoBox& extent) {
  Front f;
  for (int level : {13, 14}) {
    // n x n tiles of 360 / n by 180 / n degrees.
    const double n = 1u << level, w = 360 / n, h = 180 / n;
    const auto x0 = uint32_t((extent.west + 180) / w) - 1,
               x1 = uint32_t((extent.east + 180) / w) + 1;
    const auto y0 = uint32_t((90 - extent.north) / h) - 1,
               y1 = uint32_t((90 - extent.south) / h) + 1;
    for (uint32_t y = y0; y <= y1; ++y) {
      for (uint32_t x = x0; x <= x1; ++x) {
        const geo::TileKey k{level, x, y};
        const geo::GeoBox b = k.bounds();
        const double cx = (b.west + b.east) / 2, cy = (b.south + b.north) / 2;
        if (cy <= extent.south || cy >= extent.north || cx <= extent.west || cx >= extent.east) {
          continue;
        }
        const bool west = cx < (extent.west + extent.east) / 2;
        if ((level == 14) == west) f.keys.push_back(k), f.triangles.push_back(100 + (x % 7));
      }
    }
  }
  return f;
}

std::vector<uint64_t> per_rank(const Front& f, const std::vector<int>& owner, int ranks) {
  std::vector<uint64_t> t(ranks, 0);
  for (size_t i = 0; i < owner.size(); ++i) t[owner[i]] += f.triangles[i];
  return t;
}

TEST(QuadSplit, ActivePatchesBalanceTrianglesWhereBlocksDoNot) {
  const geo::GeoBox extent{1, 42, 2, 43};
  const Front f = uneven_front(extent);
  ASSERT_GT(f.keys.size(), 1000u);
  for (int ranks : {2, 3, 4}) {
    const auto active =
        per_rank(f, assign_quads(f.keys, f.triangles, extent, QuadSplit::active, ranks), ranks);
    const auto block =
        per_rank(f, assign_quads(f.keys, f.triangles, extent, QuadSplit::block, ranks), ranks);
    const auto quadtree =
        per_rank(f, assign_quads(f.keys, f.triangles, extent, QuadSplit::quadtree, ranks), ranks);
    EXPECT_LT(imbalance(active), 0.01) << ranks;
    EXPECT_GT(imbalance(block), 0.2) << ranks;
    // The quadtree's first cut is north/south: balanced by chance with two
    // ranks, not with four.
    if (ranks == 4) {
      EXPECT_GT(imbalance(quadtree), 0.2);
    }
    // Every quad is drawn by exactly one rank.
    EXPECT_EQ(std::accumulate(active.begin(), active.end(), uint64_t{0}),
              std::accumulate(f.triangles.begin(), f.triangles.end(), uint64_t{0}));
  }
}

// Split quads: the ranks' ranges cover every triangle of every quad exactly
// once and balance to one triangle, even with a quad much larger than the
// rest (edge-mark meshes); unsplit, such a quad limits the balance.
TEST(QuadSplit, SplitActivePatchesBalanceToOneTriangle) {
  const geo::GeoBox extent{1, 42, 2, 43};
  Front f = uneven_front(extent);
  // One quad with three times the triangles of all others together.
  f.triangles[f.triangles.size() / 2] =
      3 * std::accumulate(f.triangles.begin(), f.triangles.end(), uint64_t{0});
  const uint64_t total = std::accumulate(f.triangles.begin(), f.triangles.end(), uint64_t{0});
  for (int ranks : {2, 3, 4, 7}) {
    std::vector<uint64_t> drawn(f.keys.size(), 0), split(ranks, 0), whole(ranks, 0);
    for (int r = 0; r < ranks; ++r) {
      const auto mine = rank_triangles(f.keys, f.triangles, extent, QuadSplit::active, ranks, r,
                                       /*split_quads=*/true);
      ASSERT_EQ(mine.size(), f.keys.size());
      std::vector<uint64_t> next_first(f.keys.size(), 0);
      for (size_t i = 0; i < mine.size(); ++i) {
        if (mine[i].count == 0) continue;
        // Ranks take consecutive pieces of a quad, in rank order.
        EXPECT_EQ(mine[i].first, drawn[i]) << ranks << " ranks, rank " << r << ", quad " << i;
        drawn[i] += mine[i].count;
        split[static_cast<size_t>(r)] += mine[i].count;
      }
      for (const TriangleRange& t :
           rank_triangles(f.keys, f.triangles, extent, QuadSplit::active, ranks, r, false)) {
        EXPECT_TRUE(t.count == 0 || t.first == 0);
        whole[static_cast<size_t>(r)] += t.count;
      }
    }
    EXPECT_EQ(drawn, f.triangles) << ranks;
    EXPECT_EQ(std::accumulate(split.begin(), split.end(), uint64_t{0}), total);
    for (uint64_t t : split) EXPECT_LE(t - total / ranks, 1u) << ranks;
    EXPECT_LT(imbalance(split), 1e-4) << ranks;
    EXPECT_GT(imbalance(whole), 0.4) << ranks;  // the giant, unsplit
  }
}

// Block and quadtree never split: each quad whole on the rank assign_quads names.
TEST(QuadSplit, BlockAndQuadtreeDrawWholeQuads) {
  const geo::GeoBox extent{1, 42, 2, 43};
  const Front f = uneven_front(extent);
  for (QuadSplit split : {QuadSplit::block, QuadSplit::quadtree}) {
    const std::vector<int> owner = assign_quads(f.keys, f.triangles, extent, split, 3);
    for (int r = 0; r < 3; ++r) {
      const auto mine = rank_triangles(f.keys, f.triangles, extent, split, 3, r, true);
      for (size_t i = 0; i < mine.size(); ++i) {
        const TriangleRange expected =
            owner[i] == r ? TriangleRange{0, f.triangles[i]} : TriangleRange{};
        EXPECT_EQ(mine[i], expected);
      }
    }
  }
}

TEST(Wall, DisplaysSkipTheBezelsAndTakeTheirOffsets) {
  auto w = parse_wall(
      R"({"rows": 2, "columns": 3, "display": [100, 80], "bezel": [10, 6],
          "offsets": [[0,0],[0,0],[0,0],[0,0],[2,-3],[0,0]]})",
      "wall.json");
  ASSERT_TRUE(w) << w.error().message;
  EXPECT_EQ(w->virtual_width(), 320);
  EXPECT_EQ(w->virtual_height(), 166);
  EXPECT_EQ(w->display(0), (lod::PixelRect{0, 0, 100, 80}));
  EXPECT_EQ(w->display(2), (lod::PixelRect{220, 0, 100, 80}));
  EXPECT_EQ(w->display(4), (lod::PixelRect{112, 83, 100, 80}));
  for (const char* bad :
       {"[]", R"({"rows": 2, "columns": 2})", R"({"rows": 0, "columns": 2, "display": [1, 1]})",
        R"({"rows": 1, "columns": 2, "display": [10, 10], "bezel": [2]})",
        R"({"rows": 1, "columns": 1, "display": [10, 10], "offsets": [[5, 0]]})"}) {
    auto e = parse_wall(bad, "wall.json");
    ASSERT_FALSE(e) << bad;
    EXPECT_EQ(e.error().message.rfind("wall.json: ", 0), 0u) << e.error().message;
  }
}

TEST(Composite, KeepsTheNearerFragmentAndTheFirstOnATie) {
  Layer a{3, 1, {1, 1, 1, 255, 2, 2, 2, 255, 3, 3, 3, 255}, {0.5f, 0.0f, 0.25f}};
  const Layer b{3, 1, {9, 9, 9, 255, 8, 8, 8, 255, 7, 7, 7, 255}, {0.25f, 0.1f, 0.25f}};
  keep_nearer(a, b);
  EXPECT_EQ(a.rgba, (std::vector<uint8_t>{1, 1, 1, 255, 8, 8, 8, 255, 3, 3, 3, 255}));
  EXPECT_EQ(a.depth, (std::vector<float>{0.5f, 0.1f, 0.25f}));
}

// A layer of w x h with sky (depth 0, the same colour everywhere) on about
// half its pixels and depths from a few values, so ties occur.
Layer random_layer(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  Layer l{w, h, std::vector<uint8_t>(static_cast<size_t>(w) * h * 4), {}};
  for (int i = 0; i < w * h; ++i) {
    const bool sky = rng() % 2;
    l.depth.push_back(sky ? 0.0f : static_cast<float>(1 + rng() % 4) / 8);
    for (int c = 0; c < 4; ++c) {
      l.rgba[static_cast<size_t>(i) * 4 + c] = sky ? uint8_t{200} : static_cast<uint8_t>(rng());
    }
  }
  return l;
}

TEST(Composite, EncodedRowsMergeExactlyAsTheRawLayersAndSkipTheSky) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const Layer mine = random_layer(37, 11, seed), theirs = random_layer(37, 11, seed + 100);
    const int r0 = static_cast<int>(seed % 5), r1 = 11 - static_cast<int>(seed % 3);
    const std::vector<std::byte> message = encode_rows(theirs, r0, r1);
    // Only covered pixels travel: the run table plus 8 bytes each.
    size_t covered = 0;
    for (size_t i = static_cast<size_t>(r0) * 37; i < static_cast<size_t>(r1) * 37; ++i) {
      covered += theirs.depth[i] != 0;
    }
    EXPECT_LT(message.size(), static_cast<size_t>(r1 - r0) * 37 * 8);
    EXPECT_GE(message.size(), covered * 8);
    for (const bool theirs_win : {false, true}) {
      Layer merged = mine;
      ASSERT_TRUE(merge_encoded(merged, r0, r1, message, theirs_win));
      // The reference: raw layers, the tie winner as the base.
      Layer expected = theirs_win ? theirs : mine;
      keep_nearer(expected, theirs_win ? mine : theirs);
      for (size_t i = static_cast<size_t>(r0) * 37; i < static_cast<size_t>(r1) * 37; ++i) {
        ASSERT_EQ(merged.depth[i], expected.depth[i]) << seed << " pixel " << i;
        for (size_t c = 0; c < 4; ++c) {
          ASSERT_EQ(merged.rgba[i * 4 + c], expected.rgba[i * 4 + c]) << seed << " pixel " << i;
        }
      }
    }
  }
  // Malformed messages are errors, not reads past the end.
  Layer l = random_layer(8, 2, 7);
  std::vector<std::byte> message = encode_rows(l, 0, 2);
  EXPECT_FALSE(merge_encoded(l, 0, 1, message, false));  // runs cover 2 rows, not 1
  message.pop_back();
  EXPECT_FALSE(merge_encoded(l, 0, 2, message, false));
  EXPECT_FALSE(merge_encoded(l, 0, 2, std::span(message.data(), 2), false));
}

TEST(Compositing, ParsesTheMethodsAndRejectsOthers) {
  EXPECT_EQ(to_string(*parse_compositing("radix-k")), "radix-k:8");
  EXPECT_EQ(parse_compositing("radix-k:3")->k, 3);
  EXPECT_EQ(to_string(*parse_compositing("binary-swap")), "binary-swap");
  EXPECT_EQ(to_string(*parse_compositing("direct-send")), "direct-send");
  for (const char* bad : {"", "radix-k:", "radix-k:1", "radix-k:x", "radix-k:4x", "binary"}) {
    auto c = parse_compositing(bad);
    ASSERT_FALSE(c) << bad;
    EXPECT_EQ(c.error().message.rfind("--composite: ", 0), 0u) << c.error().message;
  }
}

TEST(Compositing, RoundsFactorTheRankCount) {
  const Compositing radix8 = *parse_compositing("radix-k"),
                    radix4 = *parse_compositing("radix-k:4");
  const Compositing swap = *parse_compositing("binary-swap"),
                    direct = *parse_compositing("direct-send");
  using V = std::vector<int>;
  EXPECT_EQ(composite_rounds(radix8, 1), V{});
  EXPECT_EQ(composite_rounds(radix8, 3), V{3});
  EXPECT_EQ(composite_rounds(radix8, 16), (V{8, 2}));
  EXPECT_EQ(composite_rounds(radix4, 16), (V{4, 4}));
  EXPECT_EQ(composite_rounds(radix4, 12), (V{4, 3}));
  EXPECT_EQ(composite_rounds(radix4, 22), (V{2, 11}));  // 11 > 4: its own round
  EXPECT_EQ(composite_rounds(swap, 8), (V{2, 2, 2}));
  EXPECT_EQ(composite_rounds(swap, 6), (V{2, 3}));
  EXPECT_EQ(composite_rounds(swap, 3), V{3});
  EXPECT_EQ(composite_rounds(direct, 12), V{12});
}

// The serial reference: per pixel the nearest fragment, the lowest rank's on a tie.
Layer composited(const std::vector<Layer>& layers) {
  Layer out = layers[0];
  for (size_t r = 1; r < layers.size(); ++r) keep_nearer(out, layers[r]);
  return out;
}

// Every rank's rounds run in one process: each round's messages are made
// from every rank's held layer before any rank merges (as over MPI), then
// the rows each rank holds at the end are compared with the reference.
TEST(Compositing, RadixKEqualsTheSerialCompositeForAnyRankCount) {
  const int w = 23, h = 13;  // fewer rows than some rank counts' pieces: empty pieces too
  for (const char* method : {"radix-k", "radix-k:2", "radix-k:3", "binary-swap", "direct-send"}) {
    const Compositing how = *parse_compositing(method);
    for (int n = 1; n <= 16; ++n) {
      std::vector<Layer> layers;
      for (int r = 0; r < n; ++r) layers.push_back(random_layer(w, h, unsigned(n * 100 + r)));
      const Layer expected = composited(layers);
      const std::vector<int> rounds = composite_rounds(how, n);
      std::vector<std::vector<RadixRound>> schedule;
      for (int r = 0; r < n; ++r) schedule.push_back(radix_schedule(r, rounds, h));
      std::vector<Layer> held = layers;
      for (size_t i = 0; i < rounds.size(); ++i) {
        // outbox[from][m]: from's message to member m of its group
        std::vector<std::vector<std::vector<std::byte>>> outbox;
        for (int r = 0; r < n; ++r) outbox.push_back(round_messages(held[r], schedule[r][i]));
        for (int r = 0; r < n; ++r) {
          const RadixRound& round = schedule[r][i];
          std::vector<std::vector<std::byte>> in(round.group.size());
          for (size_t m = 0; m < round.group.size(); ++m) {
            const int from = round.group[m];
            EXPECT_EQ(schedule[from][i].group, round.group) << method << " " << n;
            in[m] = outbox[from][round.position];
          }
          ASSERT_TRUE(merge_round(held[r], round, in)) << method << " " << n;
        }
      }
      std::vector<int> covered(h, 0);
      for (int r = 0; r < n; ++r) {
        const auto [r0, r1] = final_rows(r, rounds, h);
        for (int y = r0; y < r1; ++y) {
          ++covered[y];
          for (int x = 0; x < w; ++x) {
            const size_t p = size_t(y) * w + x;
            ASSERT_EQ(held[r].depth[p], expected.depth[p]) << method << " " << n << " rank " << r;
            for (size_t c = 0; c < 4; ++c) {
              ASSERT_EQ(held[r].rgba[p * 4 + c], expected.rgba[p * 4 + c])
                  << method << " " << n << " rank " << r << " pixel " << p;
            }
          }
        }
      }
      EXPECT_TRUE(std::all_of(covered.begin(), covered.end(), [](int c) { return c == 1; }))
          << method << " " << n;
    }
  }
}

TEST(ViewWindow, TheWholeWindowHasTheViewsFrustumAndTilesShrinkIt) {
  lod::Camera c = lod::look_at(1.5, 42.5, 1500, 40000, 0, -30, 60, 320, 240);
  const lod::View v = *lod::make_view(c);
  const lod::View whole = *lod::with_window(v, {0, 0, 320, 240});
  const auto planes = lod::window_planes(whole);
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(planes[i].normal.x, v.planes[i].normal.x, 1e-12);
    EXPECT_NEAR(planes[i].normal.y, v.planes[i].normal.y, 1e-12);
    EXPECT_NEAR(planes[i].normal.z, v.planes[i].normal.z, 1e-12);
    EXPECT_NEAR(planes[i].d, v.planes[i].d, 1e-3);
  }
  // A point projected to pixel (200, 50) is inside the window holding it only.
  const lod::Vec3 p = v.eye + (v.forward + v.right * (v.tan_half_x * (200.0 / 160 - 1)) +
                               v.up * (v.tan_half_y * (1 - 50.0 / 120))) *
                                  1000.0;
  double sx = 0, sy = 0;
  ASSERT_TRUE(v.project(p, sx, sy));
  EXPECT_NEAR(sx, 200, 1e-6);
  EXPECT_NEAR(sy, 50, 1e-6);
  const auto inside = lod::window_planes(*lod::with_window(v, {190, 40, 20, 20}));
  const auto beside = lod::window_planes(*lod::with_window(v, {211, 40, 20, 20}));
  const auto below = lod::window_planes(*lod::with_window(v, {190, 51, 20, 20}));
  EXPECT_FALSE(lod::outside(inside, p, p));
  EXPECT_TRUE(lod::outside(beside, p, p));
  EXPECT_TRUE(lod::outside(below, p, p));
  // The error metric stays the whole view's.
  EXPECT_EQ(lod::with_window(v, {0, 0, 10, 10})->pixels_per_radian, v.pixels_per_radian);
  auto outside = lod::with_window(v, {300, 0, 30, 10});
  ASSERT_FALSE(outside);
  EXPECT_NE(outside.error().message.find("30x10+300+0"), std::string::npos);
}

}  // namespace
}  // namespace relief::parallel
