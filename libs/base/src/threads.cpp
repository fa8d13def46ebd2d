#include "relief/base/threads.h"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace relief {

namespace {

// Field 19 of /proc/.../stat is the nice value. The name (field 2) is in
// parentheses and may hold spaces, so the fields are counted after its ')'.
bool read_nice(const std::filesystem::path& stat, int& nice) {
  std::ifstream in(stat);
  std::string line;
  if (!std::getline(in, line)) return false;
  const size_t close = line.rfind(')');
  if (close == std::string::npos) return false;
  std::istringstream fields(line.substr(close + 1));
  std::string field;
  for (int i = 3; i < 19; ++i) fields >> field;  // state (3) .. priority (18)
  return static_cast<bool>(fields >> nice);
}

}  // namespace

std::vector<ThreadInfo> threads_named(const std::string& name) {
  std::vector<ThreadInfo> out;
  std::error_code error;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", error)) {
    std::string comm;
    std::getline(std::ifstream(task.path() / "comm"), comm);
    if (comm != name) continue;
    ThreadInfo t;
    t.name = comm;
    if (!read_nice(task.path() / "stat", t.nice)) continue;  // the thread has just ended
    try {
      t.tid = std::stoi(task.path().filename().string());
    } catch (const std::exception&) {
      continue;
    }
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace relief
