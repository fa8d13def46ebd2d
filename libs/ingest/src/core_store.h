#pragma once
// Scratch storage for tile interiors ("cores") during a build. Cores are held
// in memory within a byte budget and written to <store>/.build/cores only
// when the budget makes them leave memory (least recently used first): a
// build whose cores fit in the budget writes no scratch at all, and one that
// does not fit reads the evicted ones back from disk. A spilled core is
// written atomically, so a killed build resumes from the cores on disk and
// computes the others again (the same values: every core is a deterministic
// function of the inputs). The directory is deleted when the build ends.
#include <cstdint>
#include <filesystem>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <unordered_map>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/tiles/raster.h"
#include "relief/tiles/tile_file.h"

namespace relief::ingest {

class CoreStore {
 public:
  // Every core has `shape` (no border); a core file of another shape is an error.
  CoreStore(std::filesystem::path dir, tiles::TileShape shape, uint64_t memory_budget_bytes);

  // Written by this build (in memory or on disk) or found on disk from an interrupted one.
  bool exists(const geo::TileKey& key) const;
  // Keeps the core in memory; cores pushed out of the budget are written to disk.
  Status write(const geo::TileKey& key, tiles::Raster core);
  // nullptr when the core does not exist (an empty tile).
  Result<std::shared_ptr<const tiles::Raster>> read(const geo::TileKey& key);
  // Every core of `level` this build wrote or found on disk, sorted by (y, x).
  std::vector<geo::TileKey> list(int level) const;
  // Whether every core of `level` written by this build is on disk, so that a
  // resumed build would find them all (the condition for a phase marker).
  bool all_on_disk(int level) const;
  // Cores written to disk so far (by eviction).
  uint64_t spilled() const;
  // Lowers the memory budget by `bytes` (never below a floor of a few
  // cores: a task needs nine at once), spilling what no longer fits.
  Status shrink_budget(uint64_t bytes);
  uint64_t budget() const;

 private:
  struct Entry {
    std::shared_ptr<const tiles::Raster> core;
    bool on_disk;
    std::list<geo::TileKey>::iterator position;  // in lru_
  };
  using Victims = std::vector<std::pair<geo::TileKey, std::shared_ptr<const tiles::Raster>>>;

  std::filesystem::path path_of(const geo::TileKey& key) const;
  // Under mutex_: inserts the core, then takes cores beyond the budget out of
  // memory; those not on disk yet are returned to be written (outside the lock).
  Victims insert_locked(const geo::TileKey& key, std::shared_ptr<const tiles::Raster> core,
                        bool on_disk);
  // Under mutex_: takes cores beyond the budget out of memory, least recently
  // used first (the newest always stays).
  Victims evict_locked();
  Status spill(Victims victims);

  std::filesystem::path dir_;
  tiles::TileShape shape_;
  uint64_t budget_;
  mutable std::mutex mutex_;
  std::unordered_map<geo::TileKey, Entry, geo::TileKeyHash> memory_;
  std::list<geo::TileKey> lru_;  // most recently used first
  uint64_t used_ = 0;
  // Out of memory but not yet renamed into place on disk: readers take them from here.
  std::unordered_map<geo::TileKey, std::shared_ptr<const tiles::Raster>, geo::TileKeyHash>
      spilling_;
  std::map<int, std::set<geo::TileKey>> written_;  // by this build, per level
  uint64_t spilled_ = 0;
};

}  // namespace relief::ingest
