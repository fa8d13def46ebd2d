// The memory cache and asynchronous loader (libs/stream) in process, on a
// real store of the N42E001 SRTM tile with small tiles (many of them), read
// through a simulated slow link or a source that injects failures.
//
// Time is a ManualClock: the link answers a request only once the test has
// moved the clock past its latency, so the tests say what had happened when
// (which loads had answered when a frame was selected), never how long
// anything took on this machine.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <tuple>

#include "relief/base/manual_clock.h"
#include "relief/lod/selection.h"
#include "relief/stream/throttled_source.h"
#include "relief/stream/tile_loader.h"
#include "relief/tiles/store_layout.h"
#include "test_support.h"

namespace relief::testing {
namespace {

using namespace std::chrono_literals;
using geo::TileKey;
using stream::TileEventKind;
using stream::TileState;

// Records which tile files a source answered, and whether any fetch ran on
// the thread that created it (the test's render thread: a frame that waited).
// Unless allowed, such a fetch fails at once rather than wait for a clock
// that the blocked thread itself should advance.
class RecordingSource final : public tiles::StoreSource {
 public:
  explicit RecordingSource(std::shared_ptr<const tiles::StoreSource> inner)
      : inner_(std::move(inner)) {}
  std::string name() const override { return inner_->name(); }
  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    const bool tile = relative.ends_with(".rtile");
    if (tile && std::this_thread::get_id() == render_thread_) {
      fetched_on_render_thread = true;
      if (!render_thread_may_fetch) return fail(relative + ": fetched on the render thread");
    }
    auto bytes = inner_->fetch(relative);
    if (tile) {
      std::lock_guard lock(mutex_);
      answered_.insert(relative);
    }
    return bytes;
  }
  size_t answered() const {
    std::lock_guard lock(mutex_);
    return answered_.size();
  }
  bool answered(const TileKey& key) const {
    std::lock_guard lock(mutex_);
    return answered_.contains(tiles::tile_relative_path(key));
  }
  // Forgets what happened so far (the loader's blocking read of level 0).
  void reset() {
    std::lock_guard lock(mutex_);
    answered_.clear();
    fetched_on_render_thread = false;
  }
  mutable std::atomic<bool> fetched_on_render_thread{false};
  std::atomic<bool> render_thread_may_fetch{false};

 private:
  std::shared_ptr<const tiles::StoreSource> inner_;
  const std::thread::id render_thread_ = std::this_thread::get_id();
  mutable std::mutex mutex_;
  mutable std::set<std::string> answered_;
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

  // Runs before the members go: no load may still be asleep on the clock
  // when the loader joins its workers.
  ~TileLoaderTest() override { clock_.set_free(true); }

  // The store through a link of `latency` on the test's clock (or through
  // `inner` instead of the local directory).
  tiles::Store& open(Clock::Duration latency,
                     std::shared_ptr<const tiles::StoreSource> inner = nullptr) {
    stream::LinkModel link;
    link.latency = std::chrono::duration_cast<std::chrono::microseconds>(latency);
    if (!inner) inner = tiles::local_source(store_dir());
    source_ = std::make_shared<RecordingSource>(stream::throttled_source(inner, link, clock_));
    source_->render_thread_may_fetch = true;  // the manifest, indices and level 0
    clock_.set_free(true);                    // arrive at once
    auto s = tiles::Store::open(source_);
    clock_.set_free(false);
    EXPECT_TRUE(s) << s.error().message;
    store_.emplace(std::move(*s));
    return *store_;
  }
  // A loader of the store on the test's clock (level 0 arrives at once), its
  // events recorded.
  stream::TileLoader& loader(stream::LoaderOptions o = {}) {
    o.clock = &clock_;
    const bool was_free = free_;
    set_free(true);
    auto l = stream::TileLoader::create(*store_, o);
    set_free(was_free);
    source_->reset();
    source_->render_thread_may_fetch = false;
    EXPECT_TRUE(l) << l.error().message;
    loader_ = std::move(*l);
    recorder_.attach(*loader_);
    return *loader_;
  }
  void set_free(bool free) {
    free_ = free;
    clock_.set_free(free);
  }
  // One frame's requests; the previous frame's events are delivered first.
  void frame(const std::vector<std::pair<TileKey, double>>& requests) {
    loader_->begin_frame();
    for (const auto& [key, priority] : requests) loader_->request(key, priority);
    loader_->end_frame();
  }
  // Waits until nothing is queued or loading (the clock must let loads end).
  void wait_idle() {
    for (int i = 0; i < 60000 && !loader_->idle(); ++i) std::this_thread::sleep_for(1ms);
    ASSERT_TRUE(loader_->idle());
    loader_->begin_frame();  // delivers the events
  }
  // The tiles of the finest level.
  std::vector<TileKey> finest() const {
    std::vector<TileKey> keys;
    for (const auto& e : store_->index(store_->manifest().max_level).entries()) {
      keys.push_back(e.key);
    }
    return keys;
  }

  static inline ScratchDir* dir_ = nullptr;
  ManualClock clock_;
  bool free_ = false;
  std::shared_ptr<RecordingSource> source_;
  std::optional<tiles::Store> store_;
  Recorder recorder_;
  std::unique_ptr<stream::TileLoader> loader_;
};

TEST_F(TileLoaderTest, LevelZeroIsResidentFromTheStart) {
  open(0ms);
  stream::TileLoader& l = loader();
  EXPECT_EQ(l.state({0, 0, 0}), TileState::Resident);
  auto tile = l.get({0, 0, 0});
  ASSERT_TRUE(tile && *tile);
  EXPECT_FALSE(*l.get(finest().front()));  // never loaded on get()
}

TEST_F(TileLoaderTest, LoadsHighestPriorityFirst) {
  open(30ms);
  stream::TileLoader& l = loader({.max_in_flight = 1});
  const auto keys = finest();
  ASSERT_GE(keys.size(), 6u);
  std::vector<std::pair<TileKey, double>> requests;
  for (size_t i = 0; i < 6; ++i) requests.emplace_back(keys[i], static_cast<double>(i));
  frame(requests);
  set_free(true);
  wait_idle();
  const auto started = recorder_.keys(TileEventKind::Started);
  ASSERT_EQ(started.size(), 6u);
  for (size_t i = 0; i < 6; ++i) EXPECT_EQ(started[i], keys[5 - i]) << i;
  EXPECT_EQ(recorder_.keys(TileEventKind::Loaded).size(), 6u);
  EXPECT_EQ(l.state(keys[0]), TileState::Resident);
}

TEST_F(TileLoaderTest, StaleRequestsAreCancelled) {
  open(100ms);
  stream::TileLoader& l = loader({.max_in_flight = 1});
  const auto keys = finest();
  ASSERT_GE(keys.size(), 8u);
  std::vector<std::pair<TileKey, double>> first;
  for (size_t i = 0; i < 6; ++i) first.emplace_back(keys[i], 1.0 + static_cast<double>(i));
  frame(first);
  // The best of them is in flight, waiting for the link; five are queued.
  ASSERT_TRUE(clock_.wait_for_sleepers(1));
  EXPECT_EQ(l.state(keys[5]), TileState::Loading);
  frame({{keys[6], 1}, {keys[7], 2}});  // the view turned: other tiles now
  set_free(true);
  wait_idle();
  EXPECT_EQ(recorder_.keys(TileEventKind::Cancelled).size(), 5u);
  const auto loaded = recorder_.keys(TileEventKind::Loaded);
  ASSERT_EQ(loaded.size(), 3u);  // the one in flight, then the new view's
  EXPECT_EQ(loaded[0], keys[5]);
  EXPECT_EQ(loaded[1], keys[7]);
  EXPECT_EQ(loaded[2], keys[6]);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(l.state(keys[i]), TileState::Absent);
  EXPECT_EQ(l.stats().cancelled, 5u);
}

// end_frame() wakes a worker per tile it queued, up to the workers, and none
// for a frame that queued nothing (each woken worker takes a core from the
// frame); the tiles queued while every worker was busy still load.
TEST_F(TileLoaderTest, FramesWakeAWorkerPerQueuedTileAndNoneForNothing) {
  open(100ms);
  stream::TileLoader& l = loader({.max_in_flight = 4});
  const auto keys = finest();
  ASSERT_GE(keys.size(), 11u);
  frame({{keys[0], 1}});
  EXPECT_EQ(l.stats().woken, 1u);
  ASSERT_TRUE(clock_.wait_for_sleepers(1));  // in flight, waiting for the link
  frame({{keys[0], 1}});                     // loading: nothing to queue
  frame({});
  EXPECT_EQ(l.stats().woken, 1u);
  std::vector<std::pair<TileKey, double>> more;
  for (size_t i = 0; i < 10; ++i) more.emplace_back(keys[i + 1], 1.0 + static_cast<double>(i));
  frame(more);  // ten queued, three workers idle: all four notified
  EXPECT_EQ(l.stats().woken, 5u);
  set_free(true);
  wait_idle();
  EXPECT_EQ(recorder_.keys(TileEventKind::Loaded).size(), 11u);
  EXPECT_EQ(l.stats().woken, 5u);
}

TEST_F(TileLoaderTest, BudgetHoldsAndPinnedTilesStay) {
  tiles::Store& store = open(0ms);
  const auto keys = finest();
  auto probe = lod::decode_heights(store, keys[0]);
  ASSERT_TRUE(probe);
  const uint64_t tile_bytes = (*probe)->byte_size();
  const uint64_t budget = 4 * tile_bytes;  // level 0 and three more
  stream::TileLoader& l = loader({.memory_budget = budget});
  // Load one tile and pin it.
  frame({{keys[0], 1}});
  wait_idle();
  const lod::TilePtr pin = *l.get(keys[0]);
  ASSERT_TRUE(pin);
  for (size_t i = 1; i < std::min<size_t>(keys.size(), 25); ++i) {
    frame({{keys[i], 1}});
    wait_idle();
    EXPECT_LE(l.stats().resident_bytes, budget) << i;
    EXPECT_EQ(l.state(keys[0]), TileState::Resident) << i;
    EXPECT_EQ(l.state({0, 0, 0}), TileState::Resident) << i;
  }
  EXPECT_GE(recorder_.keys(TileEventKind::Evicted).size(), 15u);
  EXPECT_GE(l.stats().pinned_bytes, 2 * tile_bytes);
}

// TileProvider::forget (a cache that dropped what it made of a tile): an
// unpinned resident tile is evicted and loads again when asked for; a pinned
// one, a permanent level-0 one and one that is not resident stay as they are.
TEST_F(TileLoaderTest, ForgottenTilesAreEvictedUnlessPinnedAndLoadAgain) {
  open(0ms);
  stream::TileLoader& l = loader();
  const auto keys = finest();
  ASSERT_GE(keys.size(), 3u);
  frame({{keys[0], 1}, {keys[1], 1}});
  wait_idle();
  const lod::TilePtr pin = *l.get(keys[1]);
  ASSERT_TRUE(pin);
  const uint64_t resident = l.stats().resident_bytes;
  const uint64_t bytes0 = (*l.get(keys[0]))->byte_size();  // not held
  l.forget(keys[0]);
  l.forget(keys[1]);    // pinned
  l.forget({0, 0, 0});  // level 0: kept
  l.forget(keys[2]);    // never loaded
  l.begin_frame();      // delivers the events
  EXPECT_EQ(l.state(keys[0]), TileState::Absent);
  EXPECT_EQ(l.state(keys[1]), TileState::Resident);
  EXPECT_EQ(l.state({0, 0, 0}), TileState::Resident);
  EXPECT_EQ(l.state(keys[2]), TileState::Absent);
  EXPECT_EQ(recorder_.keys(TileEventKind::Evicted), std::vector<TileKey>{keys[0]});
  EXPECT_EQ(l.stats().resident_bytes, resident - bytes0);
  EXPECT_FALSE(*l.get(keys[0]));
  frame({{keys[0], 1}});
  wait_idle();
  EXPECT_EQ(l.state(keys[0]), TileState::Resident);
  EXPECT_EQ(recorder_.keys(TileEventKind::Loaded).size(), 3u);
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

// A failed tile is not asked for again before its pause is over; the pause
// doubles with each failure up to the maximum, on the loader's clock.
TEST_F(TileLoaderTest, FailuresAreReportedNotCachedAndRetriedAfterDoublingPauses) {
  auto flaky = std::make_shared<FlakySource>(tiles::local_source(store_dir()));
  open(0ms, flaky);
  stream::TileLoader& l = loader({.retry_failed_after = 2, .retry_failed_max = 10});
  const TileKey key = finest().front();
  frame({{key, 1}});
  wait_idle();
  EXPECT_EQ(l.state(key), TileState::Failed);
  ASSERT_EQ(recorder_.keys(TileEventKind::Failed).size(), 1u);
  const auto& failed = *std::find_if(recorder_.events.begin(), recorder_.events.end(),
                                     [](const auto& e) { return e.kind == TileEventKind::Failed; });
  EXPECT_NE(failed.error.find("injected"), std::string::npos) << failed.error;
  EXPECT_FALSE(*l.get(key));
  // Each pause: asked for just before it ends, the tile stays failed (not
  // hammered); at its end it is tried again and fails again.
  uint64_t failures = 1;
  for (const auto pause : {2s, 4s, 8s, 10s, 10s}) {
    SCOPED_TRACE(pause.count());
    clock_.advance(pause - 1ms);
    frame({{key, 1}});
    wait_idle();
    EXPECT_EQ(l.stats().failed, failures);
    EXPECT_EQ(l.state(key), TileState::Failed);
    clock_.advance(1ms);
    frame({{key, 1}});
    wait_idle();
    EXPECT_EQ(l.stats().failed, ++failures);
  }
  // The server recovers; after the pause the tile loads.
  flaky->healthy = true;
  clock_.advance(10s);
  frame({{key, 1}});
  wait_idle();
  EXPECT_EQ(l.state(key), TileState::Resident);
  EXPECT_TRUE(*l.get(key));
}

// Each load that ends, resident or failed, is announced once by the worker
// that ended it (LoaderOptions::on_settled: a waiting viewer wakes up), after
// its state changed and outside the loader's lock (the listener may look).
// Nothing is announced while the loads wait for the link.
TEST_F(TileLoaderTest, AWorkerAnnouncesEachLoadThatEnds) {
  auto flaky = std::make_shared<FlakySource>(tiles::local_source(store_dir()));
  open(30ms, flaky);
  flaky->healthy = true;
  std::atomic<int> settled{0};
  std::atomic<uint64_t> ended_seen{0};  // loaded + failed seen by the last announcement
  stream::TileLoader* self = nullptr;
  stream::LoaderOptions o{.max_in_flight = 2};
  o.on_settled = [&] {
    const stream::LoaderStats s = self->stats();  // the lock is free
    ended_seen = std::max<uint64_t>(ended_seen, s.loaded + s.failed);
    ++settled;
  };
  stream::TileLoader& l = loader(o);
  self = &l;
  settled = 0;  // level 0, read at creation, is not a load that ends later
  const uint64_t at_start = l.stats().loaded;
  const auto keys = finest();
  frame({{keys[0], 3}, {keys[1], 2}, {keys[2], 1}});
  ASSERT_TRUE(clock_.wait_for_sleepers(2));
  EXPECT_EQ(settled, 0);
  set_free(true);
  wait_idle();
  EXPECT_EQ(settled, 3);
  EXPECT_EQ(ended_seen, at_start + 3);
  flaky->healthy = false;  // a failure is an end too
  frame({{keys[3], 1}});
  wait_idle();
  EXPECT_EQ(l.state(keys[3]), TileState::Failed);
  EXPECT_EQ(settled, 4);
}

// What a frame draws, to compare two selections.
std::vector<std::tuple<TileKey, int, int, int>> drawn(const lod::Selection& s) {
  std::vector<std::tuple<TileKey, int, int, int>> out;
  for (const auto& q : s.quads)
    out.emplace_back(q.key, q.finer_sides, q.coarse_sides, q.coarse_corners);
  std::sort(out.begin(), out.end());
  return out;
}

// The render thread's part of an interactive frame.
Result<lod::Selection> select_frame(lod::TerrainModel& terrain, const lod::View& view) {
  terrain.begin_frame();
  auto s = lod::select_quads(view, terrain, {});
  terrain.end_frame();
  return s;
}

const lod::Camera kOblique = lod::look_at(1.5, 42.5, 1500, 30000, 20, -35, 60, 320, 240);

// Interactive frames are drawn while the source has answered nothing: frames
// at 0, 100 and 200 ms of a 300 ms link draw level 0 and ask for the rest.
// Once the loads are done, the frame is the complete frame.
TEST_F(TileLoaderTest, FramesNeverWaitForTheSourceAndConvergeToTheCompleteFrame) {
  tiles::Store& store = open(300ms);
  stream::TileLoader& l = loader();
  const lod::MeshTopology mesh(3);
  lod::TerrainModel terrain(store, mesh, l);
  auto view = lod::make_view(kOblique);
  ASSERT_TRUE(view);
  for (int frame = 0; frame < 3; ++frame) {
    SCOPED_TRACE(frame);
    auto s = select_frame(terrain, *view);
    ASSERT_TRUE(s) << s.error().message;
    EXPECT_EQ(source_->answered(), 0u);  // no tile had arrived when this frame was drawn
    EXPECT_GT(s->stats.waiting, 0u);     // so it drew coarser quads, and asked for their data
    EXPECT_GT(l.stats().requested, 0u);
    clock_.advance(100ms);
  }
  EXPECT_FALSE(source_->fetched_on_render_thread);
  // Let the link answer; frame after frame, the view fills in.
  set_free(true);
  std::optional<lod::Selection> last;
  for (int frame = 0; frame < 64 && (!last || last->stats.waiting > 0); ++frame) {
    wait_idle();
    auto s = select_frame(terrain, *view);
    ASSERT_TRUE(s) << s.error().message;
    last = std::move(*s);
  }
  ASSERT_EQ(last->stats.waiting, 0u);
  EXPECT_FALSE(source_->fetched_on_render_thread);
  // The loader's threads measured the tiles' exact errors, not this one: all
  // but those of level 0, which the loader holds from its creation, before
  // the model asked it to.
  EXPECT_LE(terrain.error_counts().measured, store.index(0).size());
  EXPECT_GT(terrain.error_counts().prepared, 0u);
  auto local = tiles::Store::open(store_dir());
  ASSERT_TRUE(local);
  lod::TerrainModel complete(&*local, mesh, uint64_t{256} << 20);
  auto want = lod::select_quads(*view, complete, {});
  ASSERT_TRUE(want);
  EXPECT_EQ(drawn(*last), drawn(*want));
}

// A complete frame waits: it returns only once the source has answered every
// tile it draws, a round trip of the link later.
TEST_F(TileLoaderTest, CompleteFramesDrawOnlyAfterTheirLoads) {
  tiles::Store& store = open(300ms);
  source_->render_thread_may_fetch = true;  // a complete frame waits for its tiles
  set_free(true);                           // time moves as each request waits for the link
  const lod::MeshTopology mesh(3);
  lod::TerrainModel terrain(&store, mesh, uint64_t{256} << 20);
  auto view = lod::make_view(kOblique);
  ASSERT_TRUE(view);
  const auto start = clock_.now();
  auto s = lod::select_quads(*view, terrain, {});
  const auto drawn_at = clock_.now();
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_TRUE(source_->fetched_on_render_thread);
  EXPECT_GE(drawn_at - start, 300ms);
  size_t tiles = 0;
  for (const auto& q : s->quads) {
    for (const auto& w : {terrain.window(q.key), terrain.parent_window(q.key)}) {
      if (!w.tile || !store.has_tile(*w.tile)) continue;
      EXPECT_TRUE(source_->answered(*w.tile)) << w.tile->to_string();
      ++tiles;
    }
  }
  EXPECT_GT(tiles, 0u);
}

// A sudden turn: the requests of the view left behind that are still queued
// are cancelled; the new view's are not.
TEST_F(TileLoaderTest, ASuddenTurnCancelsStaleRequests) {
  tiles::Store& store = open(150ms);
  stream::TileLoader& l = loader({.max_in_flight = 2});
  const lod::MeshTopology mesh(3);
  lod::TerrainModel terrain(store, mesh, l);
  auto ahead = lod::make_view(lod::look_at(1.5, 42.5, 1000, 20000, 0, -25, 60, 320, 240));
  auto behind = lod::make_view(lod::look_at(1.5, 42.5, 1000, 20000, 180, -25, 60, 320, 240));
  ASSERT_TRUE(ahead && behind);
  ASSERT_TRUE(select_frame(terrain, *ahead));
  ASSERT_TRUE(clock_.wait_for_sleepers(2));  // two loads in flight, the rest queued
  ASSERT_GT(l.stats().queued, 0u);
  ASSERT_TRUE(select_frame(terrain, *behind));
  l.begin_frame();  // delivers the events
  const auto cancelled = recorder_.keys(TileEventKind::Cancelled);
  EXPECT_GT(cancelled.size(), 0u);
  EXPECT_EQ(l.stats().cancelled, cancelled.size());
  // Absent now: the new view did not ask for them again. None had started:
  // only the two loads in flight were spent on the view left behind.
  const auto started = recorder_.keys(TileEventKind::Started);
  EXPECT_EQ(started.size(), 2u);
  for (const auto& k : cancelled) {
    EXPECT_EQ(l.state(k), TileState::Absent) << k.to_string();
    EXPECT_EQ(std::count(started.begin(), started.end(), k), 0) << k.to_string();
  }
  // The new view converges as if the old one had never been.
  set_free(true);
  std::optional<lod::Selection> last;
  for (int frame = 0; frame < 64 && (!last || last->stats.waiting > 0); ++frame) {
    wait_idle();
    auto s = select_frame(terrain, *behind);
    ASSERT_TRUE(s);
    last = std::move(*s);
  }
  EXPECT_EQ(last->stats.waiting, 0u);
}

// The nice values of this process's threads named `name` (Linux: per thread).
std::vector<int> nice_of_threads(const std::string& name) {
  std::vector<int> out;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::string comm;
    std::getline(std::ifstream(task.path() / "comm"), comm);
    if (comm != name) continue;
    out.push_back(getpriority(PRIO_PROCESS, std::stoi(task.path().filename().string())));
  }
  return out;
}

// With worker_nice the workers run below the render thread's priority; the
// loader returns only once they all do. With worker_nice 0 (the default),
// at the creator's priority.
TEST_F(TileLoaderTest, WorkersRunAtALowerPriorityThanTheThreadThatCreatesThem) {
  open(0ms);
  const int own = getpriority(PRIO_PROCESS, gettid());
  loader({.max_in_flight = 3, .worker_nice = 10});
  std::vector<int> nice = nice_of_threads("relief-loader");
  ASSERT_EQ(nice.size(), 3u);
  for (int n : nice) EXPECT_EQ(n, std::min(19, own + 10));
  EXPECT_EQ(getpriority(PRIO_PROCESS, gettid()), own);
  loader_.reset();  // joins its workers
  EXPECT_TRUE(nice_of_threads("relief-loader").empty());
  source_->render_thread_may_fetch = true;  // level 0 again
  loader({.max_in_flight = 2});
  nice = nice_of_threads("relief-loader");
  ASSERT_EQ(nice.size(), 2u);
  for (int n : nice) EXPECT_EQ(n, own);
}

// LoaderOptions::max_preparing: however many workers have read their tiles,
// no more than that many run the Prepare step at once (the others wait for a
// slot; the render thread keeps a core). Each Prepare here holds its slot
// until the test lets it go.
TEST_F(TileLoaderTest, NoMoreThanMaxPreparingWorkersPrepareAtOnce) {
  open(0ms);
  stream::TileLoader& l = loader({.max_in_flight = 4, .max_preparing = 2});
  std::mutex mutex;
  std::condition_variable changed;
  int running = 0, most = 0, entered = 0;
  bool release = false;
  l.set_prepare([&](const TileKey&, const tiles::Raster&) {
    std::unique_lock lock(mutex);
    ++entered;
    most = std::max(most, ++running);
    changed.notify_all();
    changed.wait(lock, [&] { return release; });
    --running;
  });
  const auto open_gate = [&] {
    {
      std::lock_guard lock(mutex);
      release = true;
    }
    changed.notify_all();
  };
  // A failed assertion returns early: the gate opens so the workers can end.
  const std::unique_ptr<void, std::function<void(void*)>> opened_at_exit(
      &release, [&](void*) { open_gate(); });
  const auto keys = finest();
  ASSERT_GE(keys.size(), 4u);
  frame({{keys[0], 4}, {keys[1], 3}, {keys[2], 2}, {keys[3], 1}});
  {
    std::unique_lock lock(mutex);
    ASSERT_TRUE(changed.wait_for(lock, 60s, [&] { return entered == 2; }));
  }
  // Every tile has been read; the two workers left are at the gate. Give
  // them time to pass it, were it open.
  for (int i = 0; i < 60000 && source_->answered() < 4; ++i) std::this_thread::sleep_for(1ms);
  ASSERT_EQ(source_->answered(), 4u);
  std::this_thread::sleep_for(100ms);
  {
    std::lock_guard lock(mutex);
    EXPECT_EQ(entered, 2);
  }
  open_gate();
  wait_idle();
  EXPECT_EQ(entered, 4);
  EXPECT_EQ(most, 2);
  EXPECT_EQ(l.stats().most_preparing, 2u);  // what relief view's --stats reports
  EXPECT_EQ(recorder_.keys(TileEventKind::Loaded).size(), 4u);
}

}  // namespace
}  // namespace relief::testing
