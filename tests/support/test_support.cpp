#include "test_support.h"

#include <algorithm>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "relief/base/file_io.h"

namespace relief::testing {
namespace fs = std::filesystem;

fs::path data_dir() {
  return RELIEF_DATA_DIR;
}
std::string data(const std::string& relative) {
  return (data_dir() / relative).string();
}

size_t regular_files_under(const fs::path& dir) {
  std::error_code ec;
  size_t n = 0;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    n += it->is_regular_file() ? 1 : 0;
  }
  return n;
}

ScratchDir::ScratchDir(const std::string& name) {
  path_ = fs::temp_directory_path() / ("relief_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::string relief_binary() {
  return RELIEF_BINARY;
}

int spawn_relief(const std::vector<std::string>& args) {
  std::vector<std::string> all = {RELIEF_BINARY};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::freopen("/dev/null", "w", stdout);
    ::freopen("/dev/null", "w", stderr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  return pid;
}

namespace {
std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}
std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

RunResult run_relief(const std::vector<std::string>& args, const std::string& shell_prefix) {
  static int counter = 0;
  const fs::path base = fs::temp_directory_path() / ("relief_run_" + std::to_string(::getpid()) +
                                                     "_" + std::to_string(counter++));
  std::string cmd = shell_prefix + " " + quote(RELIEF_BINARY);
  // Appended, not `" " + quote(a)`: gcc 12 -O3 reports a false -Wrestrict on
  // `const char* + std::string&&`.
  for (const auto& a : args) cmd.append(" ").append(quote(a));
  cmd +=
      " >" + quote(base.string() + ".out") + " 2>" + quote(base.string() + ".err") + " </dev/null";
  const int status = std::system(("bash -c " + quote(cmd)).c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(base.string() + ".out");
  r.err = slurp(base.string() + ".err");
  fs::remove(base.string() + ".out");
  fs::remove(base.string() + ".err");
  return r;
}

std::vector<fs::path> temporary_files(const fs::path& dir) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->is_regular_file() && is_temporary_file(it->path())) found.push_back(it->path());
  }
  return found;
}

bool is_one_line_error(const RunResult& r, const std::string& needle) {
  return r.exit_code != 0 && std::count(r.err.begin(), r.err.end(), '\n') == 1 &&
         r.err.find(needle) != std::string::npos;
}

void SmallStoreSuite::SetUpTestSuite() {
  dir_ = new ScratchDir("small_store");
  store_ = dir_->path() / "store";
  ASSERT_EQ(run_relief({"build", data("srtm/N42E001.hgt.zip"), "--kind", "elevation", "-o",
                        store_.string(), "-q"})
                .exit_code,
            0);
}

void SmallStoreSuite::TearDownTestSuite() {
  delete dir_;
  dir_ = nullptr;
}

}  // namespace relief::testing
