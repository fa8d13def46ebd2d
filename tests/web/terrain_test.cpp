// Cesium terrain of a real store (N42E001): the tiler's tiles read by the
// specification's reader, shared edges, availability, the export command.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "qm_decoder.h"
#include "relief/base/file_io.h"
#include "relief/tiles/store.h"
#include "relief/web/terrain_tiler.h"
#include "test_support.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;
using testing::decode_quantized_mesh;
using testing::DecodedMesh;
using testing::gunzip;

class Terrain : public testing::SmallStoreSuite {
 protected:
  static std::shared_ptr<const tiles::Store> open_store() {
    auto store = tiles::Store::open(store_path());
    EXPECT_TRUE(store.has_value());
    return std::make_shared<const tiles::Store>(std::move(*store));
  }
  static const fs::path& store_path() { return store(); }
  static TerrainTiler tiler(TerrainOptions o = {}) {
    auto t = TerrainTiler::create(open_store(), o);
    EXPECT_TRUE(t.has_value());
    return std::move(*t);
  }
  static DecodedMesh decode(const TerrainTiler& t, const TerrainKey& k) {
    auto bytes = t.tile(k);
    EXPECT_TRUE(bytes.has_value()) << k.to_string();
    return decode_quantized_mesh(gunzip(*bytes));
  }
};

// The vertices on one edge, by their position along it, with heights.
std::map<uint16_t, double> edge(const DecodedMesh& m, const std::vector<uint32_t>& list,
                                bool along_v) {
  std::map<uint16_t, double> out;
  for (const uint32_t i : list) out[along_v ? m.v[i] : m.u[i]] = m.height(i);
  return out;
}

double half_step(const DecodedMesh& m) {
  return (m.max_height - m.min_height) / 32767 / 2;
}

void expect_same_edge(const DecodedMesh& a, const std::vector<uint32_t>& ea, const DecodedMesh& b,
                      const std::vector<uint32_t>& eb, bool along_v, const std::string& what) {
  const auto pa = edge(a, ea, along_v), pb = edge(b, eb, along_v);
  ASSERT_EQ(pa.size(), pb.size()) << what;
  ASSERT_GT(pa.size(), 1u) << what;
  for (auto ia = pa.begin(), ib = pb.begin(); ia != pa.end(); ++ia, ++ib) {
    ASSERT_EQ(ia->first, ib->first) << what;
    // The same lattice height, quantized over each tile's own range.
    ASSERT_NEAR(ia->second, ib->second, half_step(a) + half_step(b) + 1e-6) << what;
  }
}

TEST_F(Terrain, NeighboursOfOneLevelShareEveryEdgeVertex) {
  const TerrainTiler t = tiler();
  std::map<TerrainKey, DecodedMesh> decoded;
  const auto mesh = [&](const TerrainKey& k) -> const DecodedMesh& {
    auto it = decoded.find(k);
    if (it == decoded.end()) it = decoded.emplace(k, decode(t, k)).first;
    return it->second;
  };
  int pairs = 0;
  for (const int level : {8, t.max_level()}) {
    for (const TerrainKey& k : t.available_tiles(level)) {
      const TerrainKey east{level, k.x + 1, k.y}, north{level, k.x, k.y + 1};
      if (t.available(east)) {
        expect_same_edge(mesh(k), mesh(k).east, mesh(east), mesh(east).west, true,
                         k.to_string() + " east");
        ++pairs;
      }
      if (t.available(north)) {
        expect_same_edge(mesh(k), mesh(k).north, mesh(north), mesh(north).south, false,
                         k.to_string() + " north");
        ++pairs;
      }
    }
  }
  EXPECT_GE(pairs, 10);
}

TEST_F(Terrain, TheTwoRootTilesMeetAcrossTheAntimeridianAndAreNeverCulled) {
  const TerrainTiler t = tiler();
  const DecodedMesh west = decode(t, {0, 0, 0}), east = decode(t, {0, 1, 0});
  expect_same_edge(west, west.west, east, east.east, true, "antimeridian");
  expect_same_edge(west, west.east, east, east.west, true, "prime meridian");
  for (const DecodedMesh* m : {&west, &east}) {
    EXPECT_TRUE(std::isnan(m->hop[0]) && std::isnan(m->hop[1]) && std::isnan(m->hop[2]));
  }
  EXPECT_FALSE(std::isnan(decode(t, t.available_tiles(5).front()).hop[0]));
}

TEST_F(Terrain, VertexHeightsAreTheStoresCornerHeights) {
  const TerrainTiler t = tiler();
  const auto store = open_store();
  const int level = t.max_level();
  const double d = store->grid().sample_spacing(level);
  const TerrainKey k = t.available_tiles(level)[5];
  const DecodedMesh m = decode(t, k);
  const geo::GeoBox box = k.bounds();
  size_t checked = 0;
  for (size_t i = 0; i < m.u.size(); i += 7) {
    const double lon = box.west + m.u[i] / 32767.0 * box.width();
    const double lat = box.south + m.v[i] / 32767.0 * box.height();
    double sum = 0;
    int valid = 0;
    for (const double dx : {-d / 2, d / 2}) {
      for (const double dy : {-d / 2, d / 2}) {
        auto s = store->sample(lon + dx, lat + dy, level);
        ASSERT_TRUE(s.has_value());
        if (*s) sum += **s, ++valid;
      }
    }
    if (valid < 4) continue;
    EXPECT_NEAR(m.height(i), sum / 4, half_step(m) + 1e-3)
        << "vertex " << i << " of " << k.to_string();
    ++checked;
  }
  EXPECT_GT(checked, 20u);
  EXPECT_EQ(m.normals.size(), 2 * m.u.size());
}

TEST_F(Terrain, LayerJsonListsWhatIsAvailable) {
  TerrainOptions o;
  o.max_level = 7;
  const TerrainTiler t = tiler(o);
  const auto layer = nlohmann::json::parse(t.layer_json("n42"));
  EXPECT_EQ(layer["format"], "quantized-mesh-1.0");
  EXPECT_EQ(layer["scheme"], "tms");
  EXPECT_EQ(layer["projection"], "EPSG:4326");
  EXPECT_EQ(layer["maxzoom"], 7);
  EXPECT_EQ(layer["extensions"], nlohmann::json({"octvertexnormals", "metadata"}));
  EXPECT_EQ(layer["metadataAvailability"], 10);
  ASSERT_EQ(layer["available"].size(), 8u);
  for (int level = 0; level <= 7; ++level) {
    size_t listed = 0;
    for (const auto& r : layer["available"][level]) {
      for (uint32_t y = r["startY"]; y <= r["endY"]; ++y) {
        for (uint32_t x = r["startX"]; x <= r["endX"]; ++x) {
          EXPECT_TRUE(t.available({level, x, y}));
          ++listed;
        }
      }
    }
    EXPECT_EQ(listed, t.available_tiles(level).size()) << "level " << level;
  }
  EXPECT_FALSE(t.available({8, 0, 0}));
  EXPECT_FALSE(t.available({1, 4, 0}));
  EXPECT_FALSE(t.tile({3, 0, 0}).has_value()) << "no data there";
}

// Every tenth level's tiles carry the `metadata` extension: what is
// available in the ten levels below each (CesiumJS reads availability there).
TEST_F(Terrain, RootTilesMetadataListsTheLevelsBelowThem) {
  const TerrainTiler t = tiler();
  std::vector<std::set<TerrainKey>> listed(11);
  for (const TerrainKey root : {TerrainKey{0, 0, 0}, TerrainKey{0, 1, 0}}) {
    const DecodedMesh m = decode(t, root);
    ASSERT_FALSE(m.metadata.empty()) << root.to_string();
    const auto available = nlohmann::json::parse(m.metadata)["available"];
    ASSERT_EQ(available.size(), 10u);
    for (size_t k = 0; k < available.size(); ++k) {
      const int level = static_cast<int>(k) + 1;
      for (const auto& r : available[k]) {
        for (uint32_t y = r["startY"]; y <= r["endY"]; ++y) {
          for (uint32_t x = r["startX"]; x <= r["endX"]; ++x) {
            EXPECT_EQ(x >> level, root.x) << "inside the root's subtree";
            listed[level].insert({level, x, y});
          }
        }
      }
    }
  }
  for (int level = 1; level <= 10; ++level) {
    const auto keys = t.available_tiles(level);
    EXPECT_EQ(listed[level], std::set<TerrainKey>(keys.begin(), keys.end())) << level;
  }
  EXPECT_TRUE(decode(t, t.available_tiles(10).front()).metadata.empty())
      << "the finest level has nothing below it";
}

TEST_F(Terrain, ExportWritesEveryAvailableTileAndLayerJson) {
  testing::ScratchDir dir("terrain_export");
  const fs::path out = dir / "terrain";
  auto r = testing::run_relief({"export", store_path().string(), "--format", "quantized-mesh",
                                "--max-level", "8", "-o", out.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto text = read_text_file(out / "layer.json", 1 << 20);
  ASSERT_TRUE(text.has_value());
  const auto layer = nlohmann::json::parse(*text);
  size_t files = 0;
  for (int level = 0; level <= 8; ++level) {
    for (const auto& range : layer["available"][level]) {
      for (uint32_t y = range["startY"]; y <= range["endY"]; ++y) {
        for (uint32_t x = range["startX"]; x <= range["endX"]; ++x) {
          const fs::path tile =
              out / std::to_string(level) / std::to_string(x) / (std::to_string(y) + ".terrain");
          auto bytes = read_file(tile, 1 << 24);
          ASSERT_TRUE(bytes.has_value()) << tile;
          EXPECT_GT(decode_quantized_mesh(gunzip(*bytes)).indices.size(), 0u);
          // A tile's parent is available (a client reaches a tile through it).
          if (level > 0) {
            EXPECT_TRUE(fs::exists(out / std::to_string(level - 1) / std::to_string(x / 2) /
                                   (std::to_string(y / 2) + ".terrain")));
          }
          ++files;
        }
      }
    }
  }
  EXPECT_EQ(files + 1, testing::regular_files_under(out)) << "tiles and layer.json, nothing else";
  EXPECT_TRUE(testing::temporary_files(dir.path()).empty());
  // A second export replaces the first.
  r = testing::run_relief({"export", store_path().string(), "--format", "quantized-mesh",
                           "--max-level", "3", "-o", out.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out / "8"));
  EXPECT_TRUE(fs::exists(out / "3"));
}

TEST_F(Terrain, ExportRefusesBadArgumentsWithOneLineAndWritesNothing) {
  testing::ScratchDir dir("terrain_bad");
  const std::string s = store_path().string(), out = (dir / "t").string();
  const auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {"export", s};
    args.insert(args.end(), extra.begin(), extra.end());
    return testing::run_relief(args);
  };
  EXPECT_TRUE(testing::is_one_line_error(run({"--format", "mvt", "-o", out}), "--format"));
  EXPECT_TRUE(testing::is_one_line_error(
      run({"--format", "quantized-mesh", "--max-error", "-2", "-o", out}), "--max-error"));
  EXPECT_TRUE(testing::is_one_line_error(
      run({"--format", "quantized-mesh", "--bbox", "3,1,2", "-o", out}), "--bbox"));
  EXPECT_TRUE(testing::is_one_line_error(
      run({"--format", "quantized-mesh", "--max-level", "31", "-o", out}), "--max-level"));
  EXPECT_TRUE(testing::is_one_line_error(run({"--format", "quantized-mesh"}), "-o"));
  EXPECT_TRUE(testing::is_one_line_error(
      run({"--format", "quantized-mesh", "-o", (store_path() / "web").string()}), "-o"));
  EXPECT_TRUE(testing::is_one_line_error(
      run({"--max-level", "3", "--level", "3", "-o", out + ".tif"}), "--max-level"));
  ASSERT_TRUE(write_text_file_atomic(dir / "file", "not an export").has_value());
  EXPECT_TRUE(
      testing::is_one_line_error(run({"--format", "quantized-mesh", "-o", (dir / "file").string()}),
                                 "not an earlier web tile export"));
  fs::create_directories(dir / "other");
  ASSERT_TRUE(write_text_file_atomic(dir / "other/notes.txt", "mine").has_value());
  EXPECT_TRUE(testing::is_one_line_error(
      run({"--format", "quantized-mesh", "-o", (dir / "other").string()}),
      "not an earlier web tile export"));
  EXPECT_TRUE(fs::exists(dir / "other/notes.txt"));
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(testing::temporary_files(dir.path()).empty());
  EXPECT_TRUE(
      testing::is_one_line_error(testing::run_relief({"export", (dir / "nostore").string(),
                                                      "--format", "quantized-mesh", "-o", out}),
                                 "nostore"));
}

}  // namespace
}  // namespace relief::web

namespace relief::web {
namespace {

// The export gives web clients the elevation as relief render draws it: a
// mean of a store with itself is the store; a smoothing chain changes the
// heights; options for elevation layers on an imagery-only format fail.
TEST_F(Terrain, ExportOfFusedAndProcessedElevation) {
  testing::ScratchDir dir("terrain_layers");
  const std::string s = store_path().string();
  const auto run = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> args = {"export",      s,   "--format", "quantized-mesh",
                                     "--max-level", "9", "-o",       (dir / out).string(),
                                     "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return testing::run_relief(args);
  };
  ASSERT_EQ(run("plain", {}).exit_code, 0);
  auto r = run("fused", {"--elevation", s, "--fuse", "mean"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run("smooth", {"--elevation-op", "mean", "--elevation-param", "radius=2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string tile = "9/516/376.terrain";
  auto plain = read_file(dir / "plain" / tile, 1 << 24);
  auto fused = read_file(dir / "fused" / tile, 1 << 24);
  auto smooth = read_file(dir / "smooth" / tile, 1 << 24);
  ASSERT_TRUE(plain && fused && smooth);
  EXPECT_EQ(*plain, *fused) << "the mean of a store with itself is the store";
  const auto a = decode_quantized_mesh(gunzip(*plain)), b = decode_quantized_mesh(gunzip(*smooth));
  EXPECT_LT(b.max_height - b.min_height, a.max_height - a.min_height) << "smoothed";
  EXPECT_TRUE(
      testing::is_one_line_error(testing::run_relief({"export", s, "--level", "3", "--elevation-op",
                                                      "mean", "-o", (dir / "x.tif").string()}),
                                 "--elevation-op"));
}

}  // namespace
}  // namespace relief::web
