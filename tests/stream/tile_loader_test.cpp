// The memory cache and asynchronous loader (libs/stream) in process, on a
// real store of the N42E001 SRTM tile with small tiles (many of them), read
// through a simulated slow link or a source that injects failures.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "relief/lod/selection.h"
#include "relief/stream/throttled_source.h"
#include "relief/stream/tile_loader.h"
#include "test_support.h"

namespace relief::testing {
namespace {

using namespace std::chrono_literals;
using geo::TileKey;
using stream::TileEventKind;
using stream::TileState;

class TileLoaderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("tile_loader");
    ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                          store_dir().string(), "--tile-size", "128x64", "-q"})
                  .exit_code,
              0);
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::filesystem::path store_dir() { return dir_->path() / "store"; }

  static tiles::Store open(std::chrono::milliseconds latency) {
    stream::LinkModel link;
    link.latency = latency;
    auto s = tiles::Store::open(stream::throttled_source(tiles::local_source(store_dir()), link));
    EXPECT_TRUE(s) << s.error().message;
    return std::move(*s);
  }
  // The tiles of the finest level.
  static std::vector<TileKey> finest(const tiles::Store& s) {
    std::vector<TileKey> keys;
    for (const auto& e : s.index(s.manifest().max_level).entries()) keys.push_back(e.key);
    return keys;
  }
  static void wait_idle(stream::TileLoader& loader) {
    for (int i = 0; i < 1000 && !loader.idle(); ++i) std::this_thread::sleep_for(5ms);
    ASSERT_TRUE(loader.idle());
  }
  static inline ScratchDir* dir_ = nullptr;
};

// Events delivered to a listener, in order.
struct Recorder {
  std::vector<stream::TileEvent> events;
  void attach(stream::TileLoader& l) {
    l.subscribe([this](const stream::TileEvent& e) { events.push_back(e); });
  }
  std::vector<TileKey> keys(TileEventKind kind) const {
    std::vector<TileKey> out;
    for (const auto& e : events) {
      if (e.kind == kind) out.push_back(e.key);
    }
    return out;
  }
};

// A loader with one load in flight at a time, its events recorded.
Result<std::unique_ptr<stream::TileLoader>> one_at_a_time(const tiles::Store& store,
                                                          Recorder& rec) {
  stream::LoaderOptions o;
  o.max_in_flight = 1;
  auto loader = stream::TileLoader::create(store, o);
  if (loader) rec.attach(**loader);
  return loader;
}

TEST_F(TileLoaderTest, LevelZeroIsResidentFromTheStart) {
  tiles::Store store = open(0ms);
  auto loader = stream::TileLoader::create(store, {});
  ASSERT_TRUE(loader);
  EXPECT_EQ((*loader)->state({0, 0, 0}), TileState::Resident);
  auto tile = (*loader)->get({0, 0, 0});
  ASSERT_TRUE(tile && *tile);
  EXPECT_FALSE(*(*loader)->get(finest(store).front()));  // never loaded on get()
}

TEST_F(TileLoaderTest, LoadsHighestPriorityFirst) {
  tiles::Store store = open(30ms);
  Recorder rec;
  auto loader = one_at_a_time(store, rec);
  ASSERT_TRUE(loader);
  const auto keys = finest(store);
  ASSERT_GE(keys.size(), 6u);
  (*loader)->begin_frame();
  for (size_t i = 0; i < 6; ++i) (*loader)->request(keys[i], static_cast<double>(i));
  (*loader)->end_frame();
  wait_idle(**loader);
  (*loader)->begin_frame();  // delivers the events
  const auto started = rec.keys(TileEventKind::Started);
  ASSERT_EQ(started.size(), 6u);
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(started[i], keys[5 - i]) << i;
  EXPECT_EQ(rec.keys(TileEventKind::Loaded).size(), 6u);
  EXPECT_EQ((*loader)->state(keys[0]), TileState::Resident);
}

TEST_F(TileLoaderTest, StaleRequestsAreCancelled) {
  tiles::Store store = open(100ms);
  Recorder rec;
  auto loader = one_at_a_time(store, rec);
  ASSERT_TRUE(loader);
  const auto keys = finest(store);
  ASSERT_GE(keys.size(), 8u);
  (*loader)->begin_frame();
  for (size_t i = 0; i < 6; ++i) (*loader)->request(keys[i], 1.0 + i);
  (*loader)->end_frame();
  std::this_thread::sleep_for(20ms);  // the first load is in flight
  (*loader)->begin_frame();           // the view turned: other tiles now
  (*loader)->request(keys[6], 1);
  (*loader)->request(keys[7], 2);
  (*loader)->end_frame();
  wait_idle(**loader);
  (*loader)->begin_frame();
  EXPECT_EQ(rec.keys(TileEventKind::Cancelled).size(), 5u);
  const auto loaded = rec.keys(TileEventKind::Loaded);
  ASSERT_EQ(loaded.size(), 3u);  // the one in flight, then the new view's
  EXPECT_EQ(loaded[0], keys[5]);
  EXPECT_EQ(loaded[1], keys[7]);
  EXPECT_EQ(loaded[2], keys[6]);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ((*loader)->state(keys[i]), TileState::Absent);
  EXPECT_EQ((*loader)->stats().cancelled, 5u);
}

TEST_F(TileLoaderTest, BudgetHoldsAndPinnedTilesStay) {
  tiles::Store store = open(0ms);
  const auto keys = finest(store);
  auto probe = lod::decode_heights(store, keys[0]);
  ASSERT_TRUE(probe);
  const uint64_t tile_bytes = (*probe)->byte_size();
  stream::LoaderOptions o;
  o.memory_budget = 4 * tile_bytes;  // level 0 and three more
  auto loader = stream::TileLoader::create(store, o);
  ASSERT_TRUE(loader);
  Recorder rec;
  rec.attach(**loader);
  // Load one tile and pin it.
  (*loader)->begin_frame();
  (*loader)->request(keys[0], 1);
  (*loader)->end_frame();
  wait_idle(**loader);
  const lod::TilePtr pin = *(*loader)->get(keys[0]);
  ASSERT_TRUE(pin);
  for (size_t i = 1; i < std::min<size_t>(keys.size(), 25); ++i) {
    (*loader)->begin_frame();
    (*loader)->request(keys[i], 1);
    (*loader)->end_frame();
    wait_idle(**loader);
    const auto s = (*loader)->stats();
    EXPECT_LE(s.resident_bytes, o.memory_budget) << i;
    EXPECT_EQ((*loader)->state(keys[0]), TileState::Resident) << i;
    EXPECT_EQ((*loader)->state({0, 0, 0}), TileState::Resident) << i;
  }
  (*loader)->begin_frame();
  EXPECT_GE(rec.keys(TileEventKind::Evicted).size(), 15u);
  EXPECT_GE((*loader)->stats().pinned_bytes, 2 * tile_bytes);
}

// A source whose tile files fail until `healthy` is set.
class FlakySource final : public tiles::StoreSource {
 public:
  explicit FlakySource(std::shared_ptr<const tiles::StoreSource> inner)
      : inner_(std::move(inner)) {}
  std::string name() const override { return inner_->name(); }
  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    if (!healthy && relative.ends_with(".rtile") && !relative.starts_with("0/")) {
      return fail(relative + ": HTTP 500 (injected)");
    }
    return inner_->fetch(relative);
  }
  mutable std::atomic<bool> healthy{false};

 private:
  std::shared_ptr<const tiles::StoreSource> inner_;
};

TEST_F(TileLoaderTest, FailuresAreReportedNotCachedAndRetriedLater) {
  auto flaky = std::make_shared<FlakySource>(tiles::local_source(store_dir()));
  auto store = tiles::Store::open(flaky);
  ASSERT_TRUE(store);
  stream::LoaderOptions o;
  o.retry_failed_after = 0.3;
  auto loader = stream::TileLoader::create(*store, o);
  ASSERT_TRUE(loader);
  Recorder rec;
  rec.attach(**loader);
  const TileKey key = finest(*store).front();
  (*loader)->begin_frame();
  (*loader)->request(key, 1);
  (*loader)->end_frame();
  wait_idle(**loader);
  (*loader)->begin_frame();
  EXPECT_EQ((*loader)->state(key), TileState::Failed);
  ASSERT_EQ(rec.keys(TileEventKind::Failed).size(), 1u);
  const auto& failed = *std::find_if(rec.events.begin(), rec.events.end(),
                                     [](const auto& e) { return e.kind == TileEventKind::Failed; });
  EXPECT_NE(failed.error.find("injected"), std::string::npos) << failed.error;
  EXPECT_FALSE(*(*loader)->get(key));
  // Asked again at once: still failed, not hammered.
  (*loader)->request(key, 1);
  (*loader)->end_frame();
  wait_idle(**loader);
  EXPECT_EQ((*loader)->stats().failed, 1u);
  // After the pause it is tried again and fails again: the pause doubles.
  std::this_thread::sleep_for(350ms);
  (*loader)->begin_frame();
  (*loader)->request(key, 1);
  (*loader)->end_frame();
  wait_idle(**loader);
  EXPECT_EQ((*loader)->stats().failed, 2u);
  std::this_thread::sleep_for(350ms);  // more than the first pause, less than the second
  (*loader)->begin_frame();
  (*loader)->request(key, 1);
  (*loader)->end_frame();
  wait_idle(**loader);
  EXPECT_EQ((*loader)->stats().failed, 2u);
  EXPECT_EQ((*loader)->state(key), TileState::Failed);
  // The server recovers; after the longer pause the tile loads.
  flaky->healthy = true;
  std::this_thread::sleep_for(300ms);
  (*loader)->begin_frame();
  (*loader)->request(key, 1);
  (*loader)->end_frame();
  wait_idle(**loader);
  EXPECT_EQ((*loader)->state(key), TileState::Resident);
  EXPECT_TRUE(*(*loader)->get(key));
}

// The render thread's part of a frame (selection and requests) takes the
// same short time whatever the latency: it never waits for a load.
TEST_F(TileLoaderTest, SelectionNeverWaitsForSlowLoads) {
  tiles::Store store = open(300ms);
  auto loader = stream::TileLoader::create(store, {});
  ASSERT_TRUE(loader);
  const lod::MeshTopology mesh(3);
  lod::TerrainModel terrain(store, mesh, **loader);
  auto view = lod::make_view(lod::look_at(1.5, 42.5, 1500, 30000, 20, -35, 60, 320, 240));
  ASSERT_TRUE(view);
  uint32_t first_waiting = 0;
  for (int frame = 0; frame < 8; ++frame) {
    const auto start = std::chrono::steady_clock::now();
    terrain.begin_frame();
    auto s = lod::select_quads(*view, terrain, {});
    terrain.end_frame();
    const auto took = std::chrono::steady_clock::now() - start;
    ASSERT_TRUE(s) << s.error().message;
    if (frame == 0) first_waiting = s->stats.waiting;
    EXPECT_LT(took, 150ms) << frame;  // a load takes 300 ms
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_GT(first_waiting, 0u);
  EXPECT_FALSE((*loader)->idle());  // loads still under way: nothing waited for them
}

}  // namespace
}  // namespace relief::testing
