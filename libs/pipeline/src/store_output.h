#pragma once
// Writes a derived store: tiles go into a temporary sibling directory that is
// renamed to the output once the level indices and the manifest are written,
// so a failed or interrupted run never leaves a half-written store behind.
#include <filesystem>
#include <mutex>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/base/progress.h"
#include "relief/base/result.h"
#include "relief/tiles/store.h"

namespace relief::pipeline {

class StoreOutput {
 public:
  // Fails when `output` exists.
  static Result<StoreOutput> create(const std::filesystem::path& output, int min_level,
                                    int max_level);
  StoreOutput(StoreOutput&&) = default;
  ~StoreOutput();  // removes the temporary directory unless finished

  // Encodes and writes one bordered tile; `entry` overrides the index record's
  // bounds when given (fusion combines them from its inputs). Thread-safe.
  Status write(const geo::TileKey& key, const tiles::Raster& bordered, int border,
               const tiles::CodecOptions& codec, const tiles::IndexEntry* bounds = nullptr);
  // Writes the indices (with the tiles' geometric errors for an elevation
  // store) and `manifest` (its statistics combined from the finest level's
  // tiles), then moves the store into place.
  Status finish(tiles::Manifest manifest, Executor& executor, Progress& progress);
  uint64_t tiles_written() const { return written_; }

 private:
  StoreOutput(std::filesystem::path output, std::filesystem::path temp, int min_level,
              int max_level);
  std::filesystem::path output_, temp_;
  int min_level_ = 0;
  std::unique_ptr<std::mutex> mutex_ = std::make_unique<std::mutex>();
  std::vector<tiles::LevelIndex> indices_;
  std::vector<std::pair<geo::TileKey, tiles::SampleStats>> finest_stats_;
  uint64_t written_ = 0;
  bool finished_ = false;
};

}  // namespace relief::pipeline
