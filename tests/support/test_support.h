#pragma once
// Helpers shared by the integration tests: scratch directories, running the
// relief binary, and building stores from the bundled data.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace relief::testing {

std::filesystem::path data_dir();  // the repository's data/
std::string data(const std::string& relative);

// Regular files anywhere below `dir` (0 when it does not exist).
size_t regular_files_under(const std::filesystem::path& dir);

// A fresh directory under the system temp dir, removed by the destructor.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& p) const { return path_ / p; }

 private:
  std::filesystem::path path_;
};

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string relief_binary();

// Starts the relief binary in the background; returns its pid.
int spawn_relief(const std::vector<std::string>& args);

// Runs the relief binary with the arguments (shell-quoted), optionally prefixed
// by a shell snippet (e.g. "ulimit -f 100;").
RunResult run_relief(const std::vector<std::string>& args, const std::string& shell_prefix = "");

// A shell prefix for runs that render. Mesa's llvmpipe driver leaves ~112
// bytes behind when EGL unloads it, which LeakSanitizer reports against an
// unmapped address: leak checking is off for rendering runs of ASan builds
// (every other ASan check stays on). Normal builds ignore the variable.
inline const std::string kNoMesaLeakReport = "ASAN_OPTIONS=detect_leaks=0 ";

// A fixture that builds the N42E001 SRTM tile into a store once per suite.
class SmallStoreSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  static const std::filesystem::path& store() { return store_; }
  static ScratchDir& scratch() { return *dir_; }

 private:
  static inline ScratchDir* dir_ = nullptr;
  static inline std::filesystem::path store_;
};

// Whether `r` failed with a one-line error on stderr that contains `needle`.
bool is_one_line_error(const RunResult& r, const std::string& needle);

// Files below `dir` whose names mark an interrupted atomic write.
std::vector<std::filesystem::path> temporary_files(const std::filesystem::path& dir);

}  // namespace relief::testing
