// A build killed with SIGKILL at any point resumes to exactly the store an
// uninterrupted build writes, and never leaves a corrupt or partial tile.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <map>
#include <thread>

#include <fstream>

#include "relief/base/file_io.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

std::vector<std::string> build_args(const std::string& out,
                                    const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {"build",
                                   data("srtm/N55W004.hgt.zip"),
                                   data("srtm/N55W003.hgt.zip"),
                                   "-o",
                                   out,
                                   "--kind",
                                   "elevation",
                                   "--max-level",
                                   "11",
                                   "--threads",
                                   "1",
                                   "-q"};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

// A budget whose core cache holds about 26 of the ~150 finest interiors of
// this build (1 thread: 84 MiB reserved, a third of the rest for GDAL): the
// others are spilled to .build/cores and read back from there.
const std::vector<std::string> kSpillingMemory = {"--memory", "104MiB"};

std::map<std::string, std::vector<std::byte>> store_files(const fs::path& root) {
  std::map<std::string, std::vector<std::byte>> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (!e.is_regular_file()) continue;
    files[fs::relative(e.path(), root).generic_string()] = *read_file(e.path(), kNoSizeLimit);
  }
  return files;
}

// Waits until `ready` holds, then kills the child. False if the child finished first.
bool kill_when(int pid, const std::function<bool()>& ready) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    if (ready()) break;
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;  // finished before the kill point
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
}

struct KillPoint {
  const char* name;
  std::function<bool(const fs::path&)> ready;
};

// Kills a build of `extra` options at each point and resumes it: the store
// must be the uninterrupted build's, byte for byte. `after_kill` checks the
// killed build's directory.
void expect_resumes_to_the_same_store(const ScratchDir& dir, const std::vector<std::string>& extra,
                                      const std::vector<KillPoint>& points,
                                      const std::function<void(const fs::path&)>& after_kill) {
  const fs::path clean = dir / "clean";
  if (!fs::exists(clean / "manifest.json")) {
    ASSERT_EQ(run_relief(build_args(clean.string())).exit_code, 0);
  }
  const auto expected = store_files(clean);
  ASSERT_GT(expected.size(), 100u);
  for (const auto& point : points) {
    SCOPED_TRACE(point.name);
    const fs::path out = dir / "killed";
    fs::remove_all(out);
    const int pid = spawn_relief(build_args(out.string(), extra));
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(kill_when(pid, [&] { return point.ready(out); }));
    EXPECT_FALSE(fs::exists(out / "manifest.json")) << "killed before completion";
    after_kill(out);
    // A write cut short leaves at most its temporary file, never a partial tile.
    fs::create_directories(out / "11");
    std::ofstream(out / "11" / ("000.rtile" + std::string(kTempMarker) + "1.0")) << "partial";
    // A plain `verify` refuses an incomplete store rather than trusting it.
    EXPECT_NE(run_relief({"verify", out.string(), "-q"}).exit_code, 0);
    auto resumed = run_relief(build_args(out.string(), extra));
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    EXPECT_EQ(run_relief({"verify", out.string(), "-q"}).exit_code, 0);
    const auto got = store_files(out);
    ASSERT_EQ(got.size(), expected.size());
    for (const auto& [name, bytes] : expected) {
      auto it = got.find(name);
      ASSERT_NE(it, got.end()) << name;
      EXPECT_TRUE(it->second == bytes) << name << " differs from the uninterrupted build";
    }
  }
}

// Within the memory budget the interiors never touch the disk: a killed
// build has no scratch cores, and the resumed one computes them again.
TEST(Resume, KilledBuildsResumeToTheSameStore) {
  ScratchDir dir("resume");
  const std::vector<KillPoint> points = {
      {"as it starts", [](const fs::path& s) { return fs::exists(s / ".build/state.json"); }},
      {"while writing coarse tiles", [](const fs::path& s) { return fs::exists(s / "6"); }},
      {"while writing the finest tiles",
       [](const fs::path& s) { return regular_files_under(s / "11") >= 20; }},
  };
  expect_resumes_to_the_same_store(dir, {}, points, [](const fs::path& out) {
    EXPECT_EQ(regular_files_under(out / ".build/cores"), 0u)
        << "interiors within the budget were written";
  });
}

// Beyond the budget, interiors are spilled to .build/cores (and read back
// from there); a resumed build takes the spilled ones and computes the rest.
TEST(Resume, KilledBuildsThatSpillInteriorsResumeToTheSameStore) {
  ScratchDir dir("resume_spill");
  const fs::path cores = ".build/cores";
  const std::vector<KillPoint> points = {
      {"while warping",
       [&](const fs::path& s) { return regular_files_under(s / cores / "11") >= 5; }},
      {"while building the pyramid",
       [&](const fs::path& s) { return fs::exists(s / cores / "10"); }},
      {"while writing tiles",
       [](const fs::path& s) { return regular_files_under(s / "11") >= 20; }},
  };
  expect_resumes_to_the_same_store(dir, kSpillingMemory, points, [&](const fs::path& out) {
    EXPECT_GT(regular_files_under(out / cores), 0u);
  });
}

// Killed after the manifest's rename but before .build/ is removed (the last
// two steps cannot be one atomic step): the store is complete, and the re-run
// finishes the cleanup instead of refusing the store as existing.
TEST(Resume, KilledAfterTheManifestIsFinishedByTheRerun) {
  ScratchDir dir("resume_after_manifest");
  const fs::path clean = dir / "clean";
  ASSERT_EQ(run_relief(build_args(clean.string())).exit_code, 0);
  const auto expected = store_files(clean);

  // The scratch of this build as it stands before its cleanup: taken from a
  // build killed while writing tiles, which has all of it.
  const fs::path out = dir / "killed";
  const int pid = spawn_relief(build_args(out.string()));
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(kill_when(pid, [&] { return regular_files_under(out / "11") >= 5; }));
  const fs::path saved = dir / "saved_build";
  fs::copy(out / ".build", saved, fs::copy_options::recursive);
  ASSERT_EQ(run_relief(build_args(out.string())).exit_code, 0);
  ASSERT_FALSE(fs::exists(out / ".build"));
  fs::copy(saved, out / ".build", fs::copy_options::recursive);  // the kill point
  std::ofstream(out / "11" / ("000.rtile" + std::string(kTempMarker) + "1.0")) << "partial";
  EXPECT_NE(run_relief({"verify", out.string(), "-q"}).exit_code, 0);

  auto rerun = run_relief(build_args(out.string()));
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_FALSE(fs::exists(out / ".build"));
  auto verify = run_relief({"verify", out.string(), "-q"});
  EXPECT_EQ(verify.exit_code, 0) << verify.out << verify.err;
  const auto got = store_files(out);
  ASSERT_EQ(got.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    auto it = got.find(name);
    ASSERT_NE(it, got.end()) << name;
    EXPECT_TRUE(it->second == bytes) << name;
  }
  // Once complete and clean, the same command says the store exists.
  EXPECT_NE(run_relief(build_args(out.string())).exit_code, 0);
}

// Stopped after the scratch is removed (before the sync that makes the tiles
// durable, so the sync does not write it) and before the manifest: only the
// state file is left in .build/. The re-run computes the interiors again and
// finishes the same store.
TEST(Resume, KilledAfterTheScratchIsRemovedResumesToTheSameStore) {
  ScratchDir dir("resume_after_scratch");
  const fs::path out = dir / "killed";
  const int pid = spawn_relief(build_args(out.string()));
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(kill_when(pid, [&] { return fs::exists(out / ".build/state.json"); }));
  const std::string state = *read_text_file(out / ".build/state.json", kNoSizeLimit);
  ASSERT_EQ(run_relief(build_args(out.string())).exit_code, 0);
  const auto expected = store_files(out);
  // The kill point: every tile and level index written, the scratch gone.
  fs::remove(out / "manifest.json");
  fs::create_directories(out / ".build");
  std::ofstream(out / ".build/state.json") << state;
  EXPECT_NE(run_relief({"verify", out.string(), "-q"}).exit_code, 0);

  auto rerun = run_relief(build_args(out.string()));
  ASSERT_EQ(rerun.exit_code, 0) << rerun.err;
  EXPECT_FALSE(fs::exists(out / ".build"));
  EXPECT_EQ(run_relief({"verify", out.string(), "-q"}).exit_code, 0);
  const auto got = store_files(out);
  ASSERT_EQ(got.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    auto it = got.find(name);
    ASSERT_NE(it, got.end()) << name;
    EXPECT_TRUE(it->second == bytes) << name;
  }
}

TEST(Resume, InterruptedBuildWithOtherParametersIsRefused) {
  ScratchDir dir("resume_params");
  const fs::path out = dir / "s";
  const int pid = spawn_relief(build_args(out.string()));
  ASSERT_TRUE(kill_when(pid, [&] { return fs::exists(out / ".build/state.json"); }));
  auto other = build_args(out.string());
  other[8] = "10";  // --max-level
  auto r = run_relief(other);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("interrupted build with other parameters"), std::string::npos) << r.err;
  other.push_back("--overwrite");
  EXPECT_EQ(run_relief(other).exit_code, 0);
}

}  // namespace
}  // namespace relief::testing
