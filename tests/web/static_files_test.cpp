// Plain files of a web root (web/static_files.h): strict paths, content
// types, only regular files below a mount's folder (no link out of it, no
// FIFO, no folder), and `relief serve --web-root` answering /view/.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "http_client.h"
#include "relief/base/file_io.h"
#include "relief/web/static_files.h"
#include "servers.h"
#include "test_support.h"

namespace relief::web {
namespace {

namespace fs = std::filesystem;

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  ASSERT_TRUE(write_text_file_atomic(p, text).has_value()) << p;
}

TEST(StaticPath, AcceptsPlainNamesOnly) {
  for (const char* ok : {"index.html", "Workers/chunk-ABC123.js", "a/b/c_d-e.f.json", "x"}) {
    EXPECT_TRUE(parse_static_path(ok).has_value()) << ok;
  }
  EXPECT_EQ(parse_static_path("Assets/Textures/x.png")->size(), 3u);
  for (const char* bad :
       {"", "/", "a/", "/a", "a//b", "..", "../x", "a/../b", ".", "./a", ".hidden", "a/.git/config",
        "%2e%2e/x", "a%2fb", "a\\b", "a b", "a?b", "a:b", "\xc3\xa9.js"}) {
    EXPECT_FALSE(parse_static_path(bad).has_value()) << bad;
  }
  EXPECT_FALSE(parse_static_path(std::string(256, 'a')).has_value());
  EXPECT_TRUE(parse_static_path(std::string(255, 'a')).has_value());
  std::string deep = "a";
  for (int i = 1; i < 16; ++i) deep += "/a";
  EXPECT_TRUE(parse_static_path(deep).has_value());
  EXPECT_FALSE(parse_static_path(deep + "/a").has_value());
}

TEST(StaticPath, ContentTypesByExtension) {
  EXPECT_EQ(content_type_for("index.html"), "text/html; charset=utf-8");
  EXPECT_EQ(content_type_for("Cesium.js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(content_type_for("a.mjs"), "text/javascript; charset=utf-8");
  EXPECT_EQ(content_type_for("widgets.css"), "text/css; charset=utf-8");
  EXPECT_EQ(content_type_for("draco_decoder.wasm"), "application/wasm");
  EXPECT_EQ(content_type_for("m.glb"), "model/gltf-binary");
  EXPECT_EQ(content_type_for("t.ktx2"), "image/ktx2");
  EXPECT_EQ(content_type_for("f.woff2"), "font/woff2");
  for (const char* none : {"a.exe", "Makefile", "a.html.bak", "a.sh", "a.JS"}) {
    EXPECT_FALSE(content_type_for(none).has_value()) << none;
  }
}

class StaticFilesTree : public ::testing::Test {
 protected:
  void SetUp() override {
    write(root / "view/index.html", "<html>index</html>");
    write(root / "view/sub/app.js", "let a = 1;");
    write(root / "view/sub/.secret.js", "hidden");
    write(root / "view/notes.txt", "no type");
    write(root / "outside/secret.js", "outside");
    fs::create_symlink(root / "outside/secret.js", root / "view/link.js");
    fs::create_symlink(root / "outside", root / "view/linked");
    fs::create_directories(root / "view/folder.js");
    ASSERT_EQ(::mkfifo((root / "view/fifo.js").c_str(), 0600), 0);
    write(root / "view/big.js", std::string(2000, 'x'));
    // A mount's own folder may be a link (it is configuration).
    fs::create_directory_symlink(root / "outside", root / "mounted");
  }
  testing::ScratchDir dir{"static_files"};
  fs::path root = dir.path();
  StaticFiles files{{{"/view/", root / "view", "index.html"}, {"/lib/x/", root / "mounted", ""}},
                    1024};
};

TEST_F(StaticFilesTree, ServesRegularFilesBelowTheMount) {
  for (const char* index : {"/view/", "/view"}) {
    auto a = files.answer(index);
    ASSERT_TRUE(a.has_value()) << index;
    EXPECT_EQ(a->body, "<html>index</html>");
    EXPECT_EQ(a->content_type, "text/html; charset=utf-8");
    EXPECT_EQ(a->content_encoding, "");
  }
  auto js = files.answer("/view/sub/app.js");
  ASSERT_TRUE(js.has_value());
  EXPECT_EQ(js->body, "let a = 1;");
  auto lib = files.answer("/lib/x/secret.js");
  ASSERT_TRUE(lib.has_value());
  EXPECT_EQ(lib->body, "outside");
}

TEST_F(StaticFilesTree, AnswersNothingElse) {
  for (const char* bad :
       {"/view/link.js", "/view/linked/secret.js", "/view/folder.js", "/view/fifo.js",
        "/view/sub/.secret.js", "/view/notes.txt", "/view/missing.js", "/view/big.js",
        "/view/../outside/secret.js", "/view/sub/../sub/app.js", "/view//sub/app.js",
        "/view/%2e%2e/outside/secret.js", "/view/sub%2fapp.js", "/view/sub\\app.js", "/lib/x",
        "/lib/x/", "/viewer/", "/", "/other/index.html"}) {
    EXPECT_FALSE(files.answer(bad).has_value()) << bad;
  }
}

TEST(StaticFilesMounts, WebRootLayout) {
  const auto mounts = web_root_mounts("/w");
  ASSERT_EQ(mounts.size(), 4u);
  EXPECT_EQ(mounts[0].prefix, "/view/");
  EXPECT_EQ(mounts[0].dir, fs::path("/w/view"));
  EXPECT_EQ(mounts[0].index, "index.html");
  EXPECT_EQ(mounts[1].prefix, "/map/");
  EXPECT_EQ(mounts[1].dir, fs::path("/w/map"));
  EXPECT_EQ(mounts[1].index, "index.html");
  EXPECT_EQ(mounts[2].prefix, "/lib/cesium/");
  EXPECT_EQ(mounts[2].dir, fs::path("/w/node_modules/cesium/Build/Cesium"));
  EXPECT_EQ(mounts[3].prefix, "/lib/maplibre/");
  EXPECT_EQ(mounts[3].dir, fs::path("/w/node_modules/maplibre-gl/dist"));
}

// relief serve with a web root whose libraries are not installed: the page
// is served, the libraries get 404 and the server says why on stderr, once.
class ServePages : public testing::SmallStoreSuite {};

TEST_F(ServePages, ServesTheWebRootAndNamesWhatIsMissing) {
  testing::ScratchDir web("serve_pages");
  write(web / "view/index.html", "<html>relief</html>");
  write(web / "view/view.js", "// view");
  const int port = testing::free_port();
  const std::vector<std::string> args = {
      "serve", store().string(), "--port", std::to_string(port), "--web-root", web.path().string()};
  const int pid = testing::spawn_relief(args);
  testing::wait_for(port);
  testing::Response page = testing::get(port, "/view/");
  EXPECT_EQ(page.status, 200);
  EXPECT_EQ(page.body, "<html>relief</html>");
  EXPECT_EQ(page.headers["content-type"], "text/html; charset=utf-8");
  EXPECT_FALSE(page.headers["etag"].empty());
  EXPECT_EQ(testing::get(port, "/view/view.js").status, 200);
  EXPECT_EQ(testing::get(port, "/lib/cesium/Cesium.js").status, 404);
  EXPECT_EQ(testing::get(port, "/view/../view/view.js").status, 404);
  // The store's routes are unchanged.
  EXPECT_EQ(testing::get(port, "/terrain/layer.json").status, 200);
  EXPECT_EQ(testing::get(port, "/manifest.json").status, 200);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);

  // Stopped by timeout's SIGTERM after 2 s (time to start under a sanitizer): its stderr says what
  // is missing.
  const auto run = testing::run_relief(args, "timeout -s TERM 2");
  EXPECT_EQ(run.exit_code, 124) << run.err;
  for (const char* missing : {"/lib/cesium/ answers 404", "/lib/maplibre/ answers 404"}) {
    const size_t at = run.err.find(missing);
    EXPECT_NE(at, std::string::npos) << run.err;
    EXPECT_EQ(run.err.find(missing, at + 1), std::string::npos) << run.err;
  }
  EXPECT_NE(run.err.find("scripts/setup.sh"), std::string::npos) << run.err;

  const auto bad =
      testing::run_relief({"serve", store().string(), "--web-root", (web / "nowhere").string()});
  EXPECT_TRUE(testing::is_one_line_error(bad, "--web-root")) << bad.err;
}

}  // namespace
}  // namespace relief::web
