#pragma once
// Runs node with arguments (each single-quoted) and returns its stdout;
// `status` is pclose's (0 when node exited 0).
#include <cstdio>
#include <string>
#include <vector>

namespace relief::testing {

inline std::string run_node(const std::vector<std::string>& args, int& status) {
  std::string command = "node";
  for (const auto& a : args) command += " '" + a + "'";
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return out;
  char buffer[65536];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  status = pclose(pipe);
  return out;
}

}  // namespace relief::testing
