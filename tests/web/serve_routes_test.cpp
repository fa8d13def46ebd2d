// `relief serve` answering web clients: /terrain/layer.json and
// /terrain/{z}/{x}/{y}.terrain made on request, with ETags, HEAD, CORS, and
// a 404 for every malformed or hostile path; the store's files as before.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <thread>

#include "http_client.h"
#include "qm_decoder.h"
#include "relief/base/file_io.h"
#include "relief/tiles/codec.h"
#include "relief/tiles/store.h"
#include "relief/web/web_service.h"
#include "servers.h"
#include "test_support.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;
using testing::get;
using testing::Response;

std::vector<std::byte> bytes_of(const std::string& s) {
  const auto* p = reinterpret_cast<const std::byte*>(s.data());
  return {p, p + s.size()};
}

class ServeRoutes : public testing::SmallStoreSuite {
 protected:
  static void SetUpTestSuite() {
    SmallStoreSuite::SetUpTestSuite();
    port_ = testing::free_port();
    pid_ = testing::spawn_relief({"serve", store().string(), "--port", std::to_string(port_)});
    testing::wait_for(port_);
  }
  static void TearDownTestSuite() {
    ::kill(pid_, SIGTERM);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    SmallStoreSuite::TearDownTestSuite();
  }
  static Response raw_get(const std::string& target, const std::string& fields = "") {
    return testing::request(
        port_, "GET " + target + " HTTP/1.1\r\nHost: x\r\n" + fields + "Connection: close\r\n\r\n");
  }
  static inline int port_ = 0, pid_ = 0;
};

TEST_F(ServeRoutes, LayerJsonDescribesTheStoresTerrain) {
  const Response r = get(port_, "/terrain/layer.json");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.headers.at("content-type"), "application/json");
  EXPECT_EQ(r.headers.at("access-control-allow-origin"), "*");
  const auto layer = nlohmann::json::parse(r.body);
  EXPECT_EQ(layer["format"], "quantized-mesh-1.0");
  EXPECT_EQ(layer["tiles"], nlohmann::json({"{z}/{x}/{y}.terrain"}));
  EXPECT_EQ(layer["maxzoom"], 10);
}

TEST_F(ServeRoutes, TilesAreGzipQuantizedMeshWithEtagsAndHead) {
  const std::string target = "/terrain/10/1032/753.terrain";
  const Response r =
      raw_get(target + "?v=1.0.0&extensions=octvertexnormals",
              "Accept: application/vnd.quantized-mesh;extensions=octvertexnormals\r\n");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.headers.at("content-encoding"), "gzip");
  EXPECT_EQ(r.headers.at("content-type"), "application/vnd.quantized-mesh");
  const auto mesh = testing::decode_quantized_mesh(testing::gunzip(bytes_of(r.body)));
  EXPECT_GT(mesh.indices.size(), 0u);
  EXPECT_EQ(mesh.extensions, 1);
  // The same bytes as `relief export` writes.
  testing::ScratchDir dir("serve_routes");
  ASSERT_EQ(testing::run_relief({"export", store().string(), "--format", "quantized-mesh", "-o",
                                 (dir / "t").string(), "-q"})
                .exit_code,
            0);
  // Not `"t" + string&&`: GCC 12 at -O3 reports a false -Wrestrict there.
  auto exported = read_file(dir / "t" / target.substr(9), 1 << 24);
  ASSERT_TRUE(exported.has_value());
  EXPECT_EQ(bytes_of(r.body), *exported);

  const std::string etag = r.headers.at("etag");
  EXPECT_EQ(raw_get(target, "If-None-Match: " + etag + "\r\n").status, 304);
  EXPECT_EQ(raw_get(target, "If-None-Match: \"other\"\r\n").status, 200);
  const Response head = testing::request(
      port_, "HEAD " + target + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n", true);
  EXPECT_EQ(head.status, 200);
  EXPECT_EQ(head.headers.at("content-length"), std::to_string(r.body.size()));
  EXPECT_TRUE(head.body.empty());
}

TEST_F(ServeRoutes, MalformedAndHostilePathsGet404AndTheServerStays) {
  for (const std::string target : {"/terrain/31/0/0.terrain",
                                   "/terrain/11/4116/1514.terrain",
                                   "/terrain/1/4/0.terrain",
                                   "/terrain/1/0/2.terrain",
                                   "/terrain/01/0/0.terrain",
                                   "/terrain/-1/0/0.terrain",
                                   "/terrain/1/+0/0.terrain",
                                   "/terrain/1/0x1/0.terrain",
                                   "/terrain/a/0/0.terrain",
                                   "/terrain/1//0.terrain",
                                   "/terrain/1/0/0/0.terrain",
                                   "/terrain/1/0/0.terrain.gz",
                                   "/terrain/1/0/0",
                                   "/terrain/4294967297/0/0.terrain",
                                   "/terrain/1/4294967296/0.terrain",
                                   "/terrain/../manifest.json",
                                   "/terrain/%2e%2e/manifest.json",
                                   "/terrain/./layer.json",
                                   "/terrain/layer.json/../../../etc/passwd",
                                   "/terrain",
                                   "/terrain/",
                                   "/terrain/3/0/0.terrain",
                                   "/terrain/10/0/0.terrain"}) {
    SCOPED_TRACE(target);
    const Response r = raw_get(target);
    EXPECT_EQ(r.status, 404);
    EXPECT_EQ(r.body.find("root:"), std::string::npos);
  }
  EXPECT_EQ(get(port_, "/manifest.json").status, 200) << "store files are still served";
}

TEST_F(ServeRoutes, ConcurrentRequestsForOneTileMakeItOnce) {
  auto store = tiles::Store::open(SmallStoreSuite::store());
  ASSERT_TRUE(store.has_value());
  auto tiler = TerrainTiler::create(std::make_shared<const tiles::Store>(std::move(*store)));
  ASSERT_TRUE(tiler.has_value());
  const WebService service(std::make_shared<const TerrainTiler>(std::move(*tiler)));
  // Nothing made yet: the event loops' quick answer has nothing but the description.
  EXPECT_FALSE(service.answer_if_made("/terrain/10/1032/753.terrain").has_value());
  EXPECT_TRUE(service.answer_if_made("/terrain/layer.json").has_value());
  EXPECT_EQ(service.tiles_made(), 0u);
  std::vector<std::thread> threads;
  std::vector<std::string> bodies(8);
  for (size_t i = 0; i < bodies.size(); ++i) {
    threads.emplace_back([&, i] {
      auto a = service.answer("/terrain/10/1032/753.terrain");
      if (a) bodies[i] = a->body;
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(service.tiles_made(), 1u);
  for (const auto& b : bodies) EXPECT_EQ(b, bodies[0]);
  EXPECT_FALSE(bodies[0].empty());
  EXPECT_TRUE(service.answer("/terrain/10/1032/753.terrain").has_value());
  EXPECT_EQ(service.tiles_made(), 1u) << "answered from the cache";
  const auto quick = service.answer_if_made("/terrain/10/1032/753.terrain?v=1.0.0");
  ASSERT_TRUE(quick.has_value());
  EXPECT_EQ(quick->body, bodies[0]);
  EXPECT_EQ(quick->content_encoding, "gzip");
  EXPECT_FALSE(service.answer("/elsewhere/10/1032/753.terrain").has_value());
}

}  // namespace
}  // namespace relief::web

namespace relief::web {
namespace {

TEST_F(ServeRoutes, TerrainRgbAndTerrariumTilesWithTheirTileJson) {
  for (const std::string format : {"terrain-rgb", "terrarium"}) {
    SCOPED_TRACE(format);
    const Response description = get(port_, "/" + format + "/tiles.json");
    ASSERT_EQ(description.status, 200);
    const auto json = nlohmann::json::parse(description.body);
    EXPECT_EQ(json["encoding"], format == "terrain-rgb" ? "mapbox" : "terrarium");
    const Response tile = get(port_, "/" + format + "/10/516/378.png");
    ASSERT_EQ(tile.status, 200);
    EXPECT_EQ(tile.headers.at("content-type"), "image/png");
    EXPECT_EQ(tile.body.substr(1, 3), "PNG");
    EXPECT_EQ(tile.headers.count("content-encoding"), 0u);
    EXPECT_EQ(get(port_, "/" + format + "/10/0/0.png").status, 404) << "outside the data";
    EXPECT_EQ(get(port_, "/" + format + "/10/516/378.terrain").status, 404);
  }
  EXPECT_EQ(get(port_, "/imagery/tiles.json").status, 404) << "no imagery given";
}

// --imagery adds /imagery/; --elevation fuses layers into what web clients
// get; a wrong kind is a one-line error.
TEST_F(ServeRoutes, ImageryAndFusedElevationFromTheCommandLine) {
  testing::ScratchDir dir("serve_imagery");
  const std::string imagery = (dir / "imagery").string();
  ASSERT_EQ(testing::run_relief({"build", testing::data("imagery/RGB.byte.tif"), "--kind",
                                 "imagery", "-o", imagery, "-q"})
                .exit_code,
            0);
  const int port = testing::free_port();
  const int pid =
      testing::spawn_relief({"serve", store().string(), "--port", std::to_string(port), "--imagery",
                             imagery, "--elevation", store().string(), "--fuse", "mean"});
  testing::wait_for(port);
  const Response description = get(port, "/imagery/tiles.json");
  EXPECT_EQ(description.status, 200);
  const auto json = nlohmann::json::parse(description.body);
  const int z = json["maxzoom"];
  EXPECT_GT(z, 0);
  EXPECT_EQ(get(port, "/imagery/0/0/0.png").headers.at("content-type"), "image/png");
  const Response webp_description = get(port, "/imagery/webp/tiles.json");
  EXPECT_EQ(webp_description.status, 200);
  EXPECT_EQ(nlohmann::json::parse(webp_description.body)["tiles"][0], "{z}/{x}/{y}.webp");
  const Response webp = get(port, "/imagery/webp/0/0/0.webp");
  EXPECT_EQ(webp.status, 200);
  EXPECT_EQ(webp.headers.at("content-type"), "image/webp");
  EXPECT_EQ(webp.body.substr(0, 4), "RIFF");
  EXPECT_EQ(webp.body.substr(8, 4), "WEBP");
  EXPECT_EQ(get(port, "/imagery/webp/0/0/0.png").status, 404);
  // Cesium's geographic tiling beside it (RGB.byte's tiles are 512 x 256).
  const Response geographic = get(port, "/imagery-geo/tiles.json");
  EXPECT_EQ(geographic.status, 200);
  EXPECT_EQ(nlohmann::json::parse(geographic.body)["scheme"], "geographic");
  EXPECT_EQ(get(port, "/imagery-geo/0/0/1.png").status, 404);  // level 0 has one row
  EXPECT_EQ(get(port, "/terrain/layer.json").status, 200);
  EXPECT_EQ(get(port, "/terrain/10/1032/753.terrain").status, 200);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);

  EXPECT_TRUE(testing::is_one_line_error(testing::run_relief({"serve", store().string(), "--port",
                                                              "0", "--imagery", store().string()}),
                                         "not imagery"));
  EXPECT_TRUE(testing::is_one_line_error(
      testing::run_relief({"serve", imagery, "--port", "0", "--elevation", store().string()}),
      "--elevation"));
}

// SAR for web clients: one --texture layer through its operators and colour
// map becomes the imagery routes' layer (pipeline::colour_layer); two layers
// or a lens are one-line errors.
TEST_F(ServeRoutes, ASarLayerIsServedAsColouredImagery) {
  testing::ScratchDir dir("serve_sar");
  const std::string sar = (dir / "umbra").string();
  ASSERT_EQ(testing::run_relief({"build", testing::data("sar/umbra_mount_yasur.tif"), "--kind",
                                 "sar", "-o", sar, "-q"})
                .exit_code,
            0);
  const int port = testing::free_port();
  const int pid = testing::spawn_relief({"serve", sar, "--port", std::to_string(port), "--texture",
                                         sar, "--texture-op", "lee", "--texture-op", "log",
                                         "--texture-colormap", "viridis"});
  testing::wait_for(port);
  const Response description = get(port, "/imagery-geo/tiles.json");
  ASSERT_EQ(description.status, 200);
  const int z = nlohmann::json::parse(description.body)["maxzoom"];
  auto store = tiles::Store::open(sar);
  ASSERT_TRUE(store.has_value());
  // The tile with the most data, its west half in Cesium's geographic tiling.
  geo::TileKey key;
  uint32_t most = 0;
  for (const tiles::IndexEntry& e : store->index(z).entries()) {
    if (e.valid_count > most) most = e.valid_count, key = e.key;
  }
  const Response tile = get(port, fmt::format("/imagery-geo/{}/{}/{}.png", z, 2 * key.x, key.y));
  ASSERT_EQ(tile.status, 200);
  auto rgba =
      tiles::decode(tiles::Codec::Png, bytes_of(tile.body), tiles::SampleType::UInt8, 4, 256, 256);
  ASSERT_TRUE(rgba.has_value());
  int coloured = 0;  // viridis: never grey
  for (size_t p = 0; p < rgba->u8().size(); p += 4) {
    const auto px = rgba->u8().subspan(p, 4);
    coloured += px[3] == 255 && (px[0] != px[1] || px[1] != px[2]);
  }
  EXPECT_GT(coloured, 1000);
  EXPECT_EQ(get(port, "/imagery/tiles.json").status, 200);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);

  EXPECT_TRUE(testing::is_one_line_error(
      testing::run_relief({"serve", sar, "--port", "0", "--texture", sar, "--texture", sar}),
      "--texture"));
  EXPECT_TRUE(testing::is_one_line_error(
      testing::run_relief({"serve", sar, "--port", "0", "--texture", sar, "--lens",
                           "169.4,-19.5,500", "--lens-op", "lee"}),
      "--lens"));
}

}  // namespace
}  // namespace relief::web

namespace relief::web {
namespace {

// A store web tiles are not made from (tiles of another size) is still
// served file by file, with a note on stderr; asked for, it is an error.
TEST(ServeWithoutWebTiles, AStoreOfOtherTileSizesIsServedFileByFile) {
  testing::ScratchDir dir("serve_small_tiles");
  const std::string store = (dir / "store").string();
  ASSERT_EQ(testing::run_relief({"build", testing::data("srtm/N42E001.hgt.zip"), "--kind",
                                 "elevation", "-o", store, "--tile-size", "128x64", "-q"})
                .exit_code,
            0);
  const int port = testing::free_port();
  const int pid = testing::spawn_relief({"serve", store, "--port", std::to_string(port)});
  testing::wait_for(port);
  EXPECT_EQ(get(port, "/manifest.json").status, 200);
  EXPECT_EQ(get(port, "/terrain/layer.json").status, 404);
  ::kill(pid, SIGTERM);
  int status = -1;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_TRUE(testing::is_one_line_error(
      testing::run_relief({"serve", store, "--port", "0", "--elevation", store}), "256"));
}

}  // namespace
}  // namespace relief::web
