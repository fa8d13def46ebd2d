#pragma once
// Integrity check of a whole store: manifest, level indices, and every tile's
// header, checksum and payload; index and directory tree must agree.
#include <filesystem>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"

namespace relief::tiles {

struct VerifyReport {
  uint64_t tiles_checked = 0;
  std::vector<std::string> problems;  // one line each, naming the file
  bool ok() const { return problems.empty(); }
};

VerifyReport verify_store(const std::filesystem::path& root, Executor& executor,
                          Progress& progress);

}  // namespace relief::tiles
