#pragma once
// This process's threads as the kernel sees them (Linux: /proc/self/task),
// for statistics that show what a setting did: the nice value a worker
// actually runs at, not the one it was asked for.
#include <string>
#include <vector>

namespace relief {

struct ThreadInfo {
  int tid = 0;
  std::string name;  // pthread_setname_np, at most 15 characters
  int nice = 0;
};

// Every thread of this process named `name`; empty without /proc.
std::vector<ThreadInfo> threads_named(const std::string& name);

}  // namespace relief
