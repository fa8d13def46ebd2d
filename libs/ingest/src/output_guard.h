#pragma once
// What `relief build` may do to its output directory. --overwrite removes a
// directory, so it must be provably a relief store (or a relief build's
// scratch) and hold nothing else; and no output may hold, be, or lie inside
// one of the build's inputs.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "relief/base/result.h"

namespace relief::ingest {

// The build's scratch directory inside a store.
inline constexpr const char* kBuildDir = ".build";
inline constexpr const char* kStateName = "state.json";
// A state file holds the build's inputs and settings: a few KiB.
inline constexpr uint64_t kMaxStateBytes = uint64_t{16} << 20;

// Fails, naming the input, when `output` is an input, holds one or lies inside one.
Status check_output_apart_from_inputs(const std::filesystem::path& output,
                                      const std::vector<std::string>& inputs);

// Fails, naming what does not belong, unless `dir` holds a manifest that parses
// as a relief store's (or a build's state file) and nothing but store files:
// the manifest, level indices, tiles, the build's scratch and temporary files.
Status check_only_store_files(const std::filesystem::path& dir);

}  // namespace relief::ingest
