// Store format 2 (geometric errors in the level indexes): a format-1 store is
// refused with the way out, locally and over HTTP; `relief upgrade` turns it
// into what a fresh build writes, or writes nothing when it fails; `relief
// verify` recomputes the errors.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <cstring>
#include <fstream>

#include <nlohmann/json.hpp>

#include "relief/base/file_io.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/store.h"
#include "relief/tiles/store_layout.h"
#include "servers.h"
#include "test_support.h"

namespace relief::testing {
namespace {
namespace fs = std::filesystem;

int line_count(const std::string& s) {
  return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

std::vector<std::byte> bytes_of(const fs::path& p) {
  auto b = read_file(p, kNoSizeLimit);
  EXPECT_TRUE(b) << p;
  return b ? *b : std::vector<std::byte>{};
}

// A version 2 index file as version 1 wrote it: 16-byte records, no error.
std::vector<std::byte> as_version1(const std::vector<std::byte>& v2) {
  uint32_t cols = 0, rows = 0;
  uint64_t count = 0;
  std::memcpy(&cols, v2.data() + 20, 4);
  std::memcpy(&rows, v2.data() + 24, 4);
  std::memcpy(&count, v2.data() + 28, 8);
  const size_t records = 36 + (static_cast<size_t>(cols) * rows + 7) / 8;
  std::vector<std::byte> v1(v2.begin(), v2.begin() + static_cast<std::ptrdiff_t>(records));
  v1[8] = std::byte{1};
  for (uint64_t i = 0; i < count; ++i) {
    const auto* r = v2.data() + records + i * 20;
    v1.insert(v1.end(), r, r + 16);
  }
  const uint32_t crc = tiles::crc32_of(v1);
  const auto* c = reinterpret_cast<const std::byte*>(&crc);
  v1.insert(v1.end(), c, c + 4);
  return v1;
}

class Upgrade : public SmallStoreSuite {
 protected:
  // A copy of the store as relief wrote it before geometric errors.
  fs::path format_one_copy(const std::string& name, const fs::path& from = store()) {
    const fs::path old = dir_ / name;
    fs::copy(from, old, fs::copy_options::recursive);
    for (const auto& entry : fs::recursive_directory_iterator(old)) {
      if (entry.path().filename() != tiles::kLevelIndexName) continue;
      EXPECT_TRUE(write_file_atomic(entry.path(), as_version1(bytes_of(entry.path()))));
    }
    auto text = read_text_file(old / tiles::kManifestName, kNoSizeLimit);
    auto j = nlohmann::json::parse(*text);
    j["format_version"] = 1;
    EXPECT_TRUE(write_text_file_atomic(old / tiles::kManifestName, j.dump(2) + "\n"));
    return old;
  }
  // Every index and the manifest, to compare stores file by file.
  std::map<std::string, std::vector<std::byte>> metadata(const fs::path& root) {
    std::map<std::string, std::vector<std::byte>> files;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      const std::string rel = fs::relative(entry.path(), root).generic_string();
      if (rel == tiles::kManifestName || rel.ends_with(tiles::kLevelIndexName)) {
        files[rel] = bytes_of(entry.path());
      }
    }
    return files;
  }
  ScratchDir dir_{"upgrade"};
};

TEST_F(Upgrade, AFormatOneStoreIsRefusedWithTheWayOut) {
  const fs::path old = format_one_copy("old");
  for (const char* command : {"info", "verify"}) {
    auto r = run_relief({command, old.string()});
    EXPECT_NE(r.exit_code, 0);
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("predates geometric errors"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("`relief upgrade " + old.string() + "`"), std::string::npos) << r.err;
  }
}

TEST_F(Upgrade, AFormatOneStoreIsRefusedOverHttpToo) {
  const fs::path old = format_one_copy("served");
  const int port = free_port();
  const int pid = spawn_relief({"serve", old.string(), "--port", std::to_string(port)});
  wait_for(port);
  const std::string url = "http://127.0.0.1:" + std::to_string(port);
  auto r = run_relief({"info", url});
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("predates geometric errors"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("relief upgrade " + url), std::string::npos) << r.err;
}

TEST_F(Upgrade, GivesWhatAFreshBuildWrites) {
  const fs::path old = format_one_copy("old");
  auto r = run_relief({"upgrade", old.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("upgraded from store format version 1 to 2"), std::string::npos) << r.out;
  EXPECT_EQ(metadata(old), metadata(store()));
  EXPECT_EQ(run_relief({"verify", old.string(), "-q"}).exit_code, 0);
  // Once is enough.
  r = run_relief({"upgrade", old.string(), "-q"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("already at store format version 2"), std::string::npos) << r.out;
}

// A current manifest over version-1 indices (an upgrade killed before its
// manifest): readers send the user to upgrade, and upgrade does not answer
// "nothing to do".
TEST_F(Upgrade, OldIndicesUnderACurrentManifestAreUpgradedToo) {
  const fs::path old = format_one_copy("half");
  fs::copy_file(store() / tiles::kManifestName, old / tiles::kManifestName,
                fs::copy_options::overwrite_existing);
  EXPECT_NE(run_relief({"info", old.string()}).err.find("relief upgrade"), std::string::npos);
  auto r = run_relief({"upgrade", old.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("upgraded from store format version 1 to 2"), std::string::npos) << r.out;
  EXPECT_EQ(metadata(old), metadata(store()));
}

// A version-1 index that is also damaged (its count disagrees with its
// records, checksum recomputed) under a current manifest: readers used to
// send the user to `relief upgrade`, which then said "nothing to do". Both
// now name the damage, and neither succeeds.
TEST_F(Upgrade, ADamagedOldIndexIsTheSameErrorToReadersAndUpgrade) {
  const fs::path old = dir_ / "damaged";
  fs::copy(store(), old, fs::copy_options::recursive);
  const fs::path index = old / tiles::level_index_relative_path(8);
  std::vector<std::byte> bytes = as_version1(bytes_of(index));
  uint64_t count = 0;
  std::memcpy(&count, bytes.data() + 28, 8);
  ++count;
  std::memcpy(bytes.data() + 28, &count, 8);
  ASSERT_GT(bytes.size(), 36u);
  // Erased, not resized: GCC at -O1 (the asan preset) cannot rule out a
  // wrapped size in resize(size - 4) and fails the build on it.
  bytes.erase(bytes.end() - 4, bytes.end());
  const uint32_t crc = tiles::crc32_of(bytes);
  const auto* c = reinterpret_cast<const std::byte*>(&crc);
  bytes.insert(bytes.end(), c, c + 4);
  ASSERT_TRUE(write_file_atomic(index, bytes));
  const std::string damage = index.string() + ": level index is truncated or inconsistent";
  auto info = run_relief({"info", old.string()});
  EXPECT_TRUE(is_one_line_error(info, damage)) << info.err;
  auto r = run_relief({"upgrade", old.string(), "-q"});
  EXPECT_TRUE(is_one_line_error(r, damage)) << r.out << r.err;
  EXPECT_EQ(r.out.find("nothing to do"), std::string::npos) << r.out;
}

// Imagery has no heights: errors 0, only the format changes.
TEST_F(Upgrade, ImageryStoresOnlyChangeFormat) {
  const fs::path fresh = dir_ / "rgb";
  ASSERT_EQ(run_relief({"build", data("imagery/RGB.byte.tif"), "--kind", "imagery", "-o",
                        fresh.string(), "-q"})
                .exit_code,
            0);
  const fs::path old = format_one_copy("rgb_old", fresh);
  auto r = run_relief({"upgrade", old.string(), "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(metadata(old), metadata(fresh));
  auto opened = tiles::Store::open(old);
  ASSERT_TRUE(opened) << opened.error().message;
  for (int l = opened->manifest().min_level; l <= opened->manifest().max_level; ++l) {
    for (const auto& e : opened->index(l).entries()) EXPECT_EQ(e.error, 0.0f);
  }
}

TEST_F(Upgrade, AFailedUpgradeWritesNothing) {
  const fs::path old = format_one_copy("broken");
  const auto before = metadata(old);
  // A tile of the finest level is unreadable: no error can be computed above it.
  fs::path victim;
  for (const auto& entry : fs::recursive_directory_iterator(old / "10")) {
    if (entry.path().extension() == tiles::kTileExtension) victim = entry.path();
  }
  ASSERT_FALSE(victim.empty());
  fs::resize_file(victim, 100);
  auto r = run_relief({"upgrade", old.string(), "-q"});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(victim.string()), std::string::npos) << r.err;
  EXPECT_EQ(metadata(old), before);
  EXPECT_TRUE(temporary_files(old).empty());
}

TEST_F(Upgrade, VerifyRecomputesTheErrors) {
  const fs::path copy = dir_ / "copy";
  fs::copy(store(), copy, fs::copy_options::recursive);
  auto opened = tiles::Store::open(copy);
  ASSERT_TRUE(opened) << opened.error().message;
  const int level = opened->manifest().max_level - 2;
  tiles::LevelIndex index = opened->index(level);
  const tiles::IndexEntry e = index.entries().at(0);
  ASSERT_GT(e.error, 0.0f);
  index.set_error(e.key, e.error * 0.5f);  // a consistent, checksummed, wrong value
  ASSERT_TRUE(tiles::write_level_index(copy, index));
  auto r = run_relief({"verify", copy.string(), "-q"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  const std::string index_path = (copy / tiles::level_index_relative_path(level)).string();
  EXPECT_NE(r.err.find(index_path + ": tile " + e.key.to_string() + " has a geometric error"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace relief::testing
