#include "relief/base/file_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "relief/base/units.h"

namespace relief {
namespace fs = std::filesystem;

TEST(FileIo, AtomicWriteCreatesDirectoriesAndLeavesNoTemporaries) {
  const fs::path dir = fs::temp_directory_path() / "relief_file_io_test";
  fs::remove_all(dir);
  ASSERT_TRUE(write_text_file_atomic(dir / "a/b/c.txt", "hello"));
  ASSERT_TRUE(write_text_file_atomic(dir / "a/b/c.txt", "replaced"));
  EXPECT_EQ(*read_text_file(dir / "a/b/c.txt", kNoSizeLimit), "replaced");
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    EXPECT_FALSE(is_temporary_file(e.path())) << e.path();
  }
  fs::remove_all(dir);
}

TEST(FileIo, ErrorsNameTheFile) {
  auto r = read_file("/nonexistent/relief/x", kNoSizeLimit);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/nonexistent/relief/x"), std::string::npos);
  auto w = write_text_file_atomic("/proc/relief-cannot-write/x", "y");
  ASSERT_FALSE(w);
  EXPECT_NE(w.error().message.find("relief-cannot-write"), std::string::npos);
}

// Reads end: a FIFO (which would block until a writer came), a symlink to
// /dev/zero (which never ends) and a directory are refused by their type
// before anything is read, and a file larger than the caller's cap (here a
// sparse one) by its size; a file within the cap reads whole.
TEST(FileIo, ReadsAreOfRegularFilesWithinTheirCap) {
  const fs::path dir = fs::temp_directory_path() / "relief_file_io_read";
  fs::remove_all(dir);
  fs::create_directories(dir);
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_symlink("/dev/zero", dir / "zero");
  { std::ofstream sparse(dir / "sparse", std::ios::binary); }
  fs::resize_file(dir / "sparse", uint64_t{1} << 30);
  ASSERT_TRUE(write_text_file_atomic(dir / "small", "12345"));
  const auto refused = [&](const std::string& name, uint64_t cap, const std::string& why) {
    const auto r = read_file(dir / name, cap);
    ASSERT_FALSE(r) << name;
    EXPECT_NE(r.error().message.find((dir / name).string()), std::string::npos)
        << r.error().message;
    EXPECT_NE(r.error().message.find(why), std::string::npos) << r.error().message;
  };
  refused("fifo", kNoSizeLimit, "is a FIFO, not a regular file");
  refused("zero", kNoSizeLimit, "is a character device, not a regular file");
  refused(".", kNoSizeLimit, "is a directory, not a regular file");
  refused("sparse", uint64_t{1} << 20, "the most this file can hold");
  refused("small", 4, "5 bytes, more than 4 B");
  EXPECT_EQ(read_text_file(dir / "small", 5).value_or(""), "12345");
  EXPECT_TRUE(check_regular_file(dir / "small"));
  EXPECT_FALSE(check_regular_file(dir / "fifo"));
  fs::remove_all(dir);
}

// Renaming over a device node would replace it with a regular file (as root,
// `export -o /dev/full` did), and opening a FIFO blocks: both are refused, and
// nothing is created beside them.
TEST(FileIo, AtomicWriteRefusesToReplaceNonRegularFiles) {
  const fs::path dir = fs::temp_directory_path() / "relief_file_io_special";
  fs::remove_all(dir);
  fs::create_directories(dir / "subdir");
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0644), 0);
  fs::create_symlink("/dev/null", dir / "null_link");
  // The FIFO and the directory come first: a writer that failed to refuse them
  // stops the test (ASSERT) before it could replace the machine's /dev/null.
  const std::pair<fs::path, std::string> cases[] = {{dir / "fifo", "FIFO"},
                                                    {dir / "subdir", "directory"},
                                                    {dir / "null_link", "character device"},
                                                    {"/dev/null", "character device"}};
  for (const auto& [target, what] : cases) {
    SCOPED_TRACE(target.string());
    auto w = write_text_file_atomic(target, "replaced");
    ASSERT_FALSE(w);
    EXPECT_NE(w.error().message.find(target.string()), std::string::npos) << w.error().message;
    EXPECT_NE(w.error().message.find(what), std::string::npos) << w.error().message;
    EXPECT_EQ(w.error().message.find('\n'), std::string::npos);
  }
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
  EXPECT_TRUE(fs::is_symlink(dir / "null_link"));
  EXPECT_TRUE(fs::is_directory(dir / "subdir"));
  for (const auto& e : fs::directory_iterator("/dev")) {
    EXPECT_FALSE(e.path().filename().string().starts_with("null.tmp.")) << e.path();
  }
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    EXPECT_FALSE(is_temporary_file(e.path())) << e.path();
  }
  // A symlink to a regular file is replaced as before (the link, not its target).
  ASSERT_TRUE(write_text_file_atomic(dir / "real.txt", "real"));
  fs::create_symlink(dir / "real.txt", dir / "real_link");
  EXPECT_TRUE(write_text_file_atomic(dir / "real_link", "new"));
  EXPECT_EQ(*read_text_file(dir / "real.txt", kNoSizeLimit), "real");
  EXPECT_EQ(*read_text_file(dir / "real_link", kNoSizeLimit), "new");
  fs::remove_all(dir);
}

// A process id that was just in use and now is not.
pid_t dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

TEST(FileIo, StaleTemporariesOfDeadProcessesAreRemovedOthersKept) {
  const fs::path dir = fs::temp_directory_path() / "relief_file_io_stale";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const pid_t dead = dead_pid();
  const fs::path out = dir / "out";
  const fs::path stale_dir = dir / fmt::format("out.tmp.{}", dead);
  const fs::path stale_file = dir / fmt::format("out.tmp.{}.3", dead);
  const fs::path mine = temporary_name(out);   // this process: alive
  const fs::path other = dir / "other.tmp.1";  // another output's
  const fs::path no_pid = dir / "out.tmp.x";   // not one of ours
  fs::create_directories(stale_dir / "3");
  std::ofstream(stale_dir / "3" / "a.rtile") << "x";
  for (const auto& p : {stale_file, mine, other, no_pid}) std::ofstream(p) << "x";
  EXPECT_TRUE(is_stale_temporary_file(stale_dir));
  EXPECT_FALSE(is_stale_temporary_file(mine));
  auto removed = remove_stale_temporaries_of(out);
  ASSERT_TRUE(removed) << removed.error().message;
  EXPECT_EQ(*removed, 2u);
  EXPECT_FALSE(fs::exists(stale_dir));
  EXPECT_FALSE(fs::exists(stale_file));
  for (const auto& p : {mine, other, no_pid}) EXPECT_TRUE(fs::exists(p)) << p;
  fs::remove_all(dir);
}

TEST(Units, SizesBeyondWhatFitsAreRefused) {
  EXPECT_EQ(*parse_byte_size("2GiB"), uint64_t{2} << 30);
  EXPECT_EQ(*parse_byte_size("15TiB"), uint64_t{15} << 40);
  for (const char* text : {"99999999TiB", "1e30", "inf", "nan", "-1"}) {
    auto r = parse_byte_size(text);
    EXPECT_FALSE(r) << text << " gave " << (r ? *r : 0);
  }
}

}  // namespace relief
