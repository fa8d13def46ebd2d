#include "relief/base/file_io.h"

#include <gtest/gtest.h>

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

}  // namespace relief
