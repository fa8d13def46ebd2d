#include "relief/base/file_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>

namespace relief {
namespace fs = std::filesystem;

TEST(FileIo, AtomicWriteCreatesDirectoriesAndLeavesNoTemporaries) {
  const fs::path dir = fs::temp_directory_path() / "relief_file_io_test";
  fs::remove_all(dir);
  ASSERT_TRUE(write_text_file_atomic(dir / "a/b/c.txt", "hello"));
  ASSERT_TRUE(write_text_file_atomic(dir / "a/b/c.txt", "replaced"));
  EXPECT_EQ(*read_text_file(dir / "a/b/c.txt"), "replaced");
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    EXPECT_FALSE(is_temporary_file(e.path())) << e.path();
  }
  fs::remove_all(dir);
}

TEST(FileIo, ErrorsNameTheFile) {
  auto r = read_file("/nonexistent/relief/x");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/nonexistent/relief/x"), std::string::npos);
  auto w = write_text_file_atomic("/proc/relief-cannot-write/x", "y");
  ASSERT_FALSE(w);
  EXPECT_NE(w.error().message.find("relief-cannot-write"), std::string::npos);
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
  EXPECT_EQ(*read_text_file(dir / "real.txt"), "real");
  EXPECT_EQ(*read_text_file(dir / "real_link"), "new");
  fs::remove_all(dir);
}

}  // namespace relief
