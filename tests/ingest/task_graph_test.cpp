// The build's task graph (task_graph.h): every task once, after its
// prerequisites, in a fixed order on one worker; and a build of many small
// tiles gives the same bytes on one worker and on two, within the memory
// budget and beyond it.
#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <map>
#include <mutex>
#include <random>

#include "relief/base/file_io.h"
#include "relief/ingest/build.h"
#include "task_graph.h"
#include "test_support.h"
#include "writeback.h"

namespace relief::ingest {
namespace {
namespace fs = std::filesystem;

TEST(TaskGraph, OneWorkerRunsByClassThenInTheOrderTasksBecameReady) {
  TaskGraph graph;
  const size_t warp_a = graph.add(0), warp_b = graph.add(0);
  const size_t tile = graph.add(2), parent = graph.add(1);
  graph.depend(tile, warp_a);
  graph.depend(parent, warp_a);
  graph.depend(parent, warp_b);
  const size_t late = graph.add(0);  // ready from the start: runs before the others
  std::vector<size_t> order;
  InlineExecutor inline_executor;
  graph.run(inline_executor, [&](size_t id) { order.push_back(id); });
  EXPECT_EQ(order, (std::vector<size_t>{warp_a, warp_b, late, parent, tile}));
}

TEST(TaskGraph, TwoWorkersRunEveryTaskOnceAfterItsPrerequisites) {
  std::mt19937 random(7);
  TaskGraph graph;
  std::vector<std::vector<size_t>> prerequisites;
  for (size_t id = 0; id < 2000; ++id) {
    graph.add(static_cast<int>(random() % TaskGraph::kClasses));
    prerequisites.emplace_back();
    for (int k = 0; id > 0 && k < 3; ++k) {
      const size_t p = random() % id;
      graph.depend(id, p);
      prerequisites.back().push_back(p);
    }
  }
  std::vector<std::atomic<int>> runs(graph.size());
  std::atomic<size_t> out_of_order{0};
  ThreadExecutor executor(2);
  graph.run(executor, [&](size_t id) {
    for (size_t p : prerequisites[id]) out_of_order += runs[p].load() != 1;
    ++runs[id];
  });
  EXPECT_EQ(out_of_order.load(), 0u);
  for (size_t id = 0; id < graph.size(); ++id) EXPECT_EQ(runs[id].load(), 1) << id;
}

// While one warp runs, the second worker takes ready work of another class
// rather than a second warp, which would wait for the first one's reads.
TEST(TaskGraph, ASecondWarpWaitsWhileOtherWorkIsReady) {
  TaskGraph graph;
  const size_t first = graph.add(0), second = graph.add(0), tile = graph.add(2);
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<size_t> started;
  ThreadExecutor executor(2);
  graph.run(executor, [&](size_t id) {
    std::unique_lock lock(mutex);
    started.push_back(id);
    changed.notify_all();
    // The first warp holds its worker until the other worker has taken a task.
    if (id == first) changed.wait(lock, [&] { return started.size() > 1; });
  });
  ASSERT_EQ(started.size(), 3u);
  EXPECT_EQ(started[0], first);
  EXPECT_EQ(started[1], tile);
  EXPECT_EQ(started[2], second);
}

TEST(Writeback, StartsFilesAndIgnoresMissingOnes) {
  testing::ScratchDir dir("writeback");
  const std::string text = "a tile's bytes";
  ASSERT_TRUE(write_text_file_atomic(dir / "tile", text));
  {
    Writeback writeback;
    writeback.start(dir / "tile");
    writeback.start(dir / "missing");
  }
  EXPECT_EQ(*read_text_file(dir / "tile", kNoSizeLimit), text);
}

std::map<std::string, std::vector<std::byte>> files_under(const fs::path& root) {
  std::map<std::string, std::vector<std::byte>> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file())
      files[fs::relative(e.path(), root).generic_string()] = *read_file(e.path(), kNoSizeLimit);
  }
  return files;
}

// Builds the same store with one worker and with two, expects the same bytes.
void expect_same_store_on_one_and_two_workers(int tile_log2_height, int max_level,
                                              uint64_t memory_budget, size_t min_tiles) {
  testing::ScratchDir dir("task_graph_build");
  BuildOptions o;
  o.inputs = {testing::data("srtm/N55W004.hgt.zip"), testing::data("srtm/N55W003.hgt.zip")};
  o.tile_log2_height = tile_log2_height;
  o.max_level = max_level;
  o.memory_budget = memory_budget;
  NullProgress progress;
  o.output = dir / "one";
  InlineExecutor one;
  auto a = build_store(o, one, progress);
  ASSERT_TRUE(a) << a.error().message;
  o.output = dir / "two";
  ThreadExecutor two(2);
  auto b = build_store(o, two, progress);
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_GT(a->tiles_written, min_tiles);
  EXPECT_EQ(a->tiles_written, b->tiles_written);
  const auto expected = files_under(dir / "one");
  const auto got = files_under(dir / "two");
  ASSERT_EQ(got.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    auto it = got.find(name);
    ASSERT_NE(it, got.end()) << name;
    EXPECT_TRUE(it->second == bytes) << name << " differs between one worker and two";
  }
}

// Many small tiles (32 x 16 samples, 810 of them), so that warps, parents and
// tiles of several levels are in flight together.
TEST(TaskGraphBuild, TwoWorkersWriteTheStoreOneWorkerWrites) {
  expect_same_store_on_one_and_two_workers(4, 12, uint64_t{1} << 30, 800);
}

// A budget whose core cache holds about 26 of the ~150 finest interiors (2
// workers: 96 MiB reserved, a third of the rest for GDAL): spilled interiors
// are read back while other tasks run.
TEST(TaskGraphBuild, TwoWorkersBeyondTheMemoryBudgetWriteTheSameStore) {
  expect_same_store_on_one_and_two_workers(8, 11, uint64_t{116} << 20, 150);
}

}  // namespace
}  // namespace relief::ingest
