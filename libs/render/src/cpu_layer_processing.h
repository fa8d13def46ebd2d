#pragma once
// Texture layers processed on the CPU (ProcessOn::cpu, docs/gpu-processing.md
// "Where layers are processed"): a layer tile goes through its chain with the
// CPU reference (gpuprocess::run_chain_cpu) on worker threads, never on the GL
// thread of an interactive frame; the renderer picks the result up in a later
// frame, uploads it and maps and composites it on the GPU (or, when the layer
// alone makes the composite, the worker maps it to colours too and the frame
// only uploads them). Results are kept under (layer, tile, parameter version)
// until taken or outdated. An interactive frame may wait for the workers
// (wait_idle) within its processing budget: processing is not I/O.
//
// Thread safety: every member is called from the renderer's thread; the
// workers only touch the queue and the results, under the mutex.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <tuple>
#include <vector>

#include "relief/base/result.h"
#include "relief/geo/tile_key.h"
#include "relief/gpuprocess/chain.h"
#include "relief/gpuprocess/composite.h"
#include "relief/lod/tile_provider.h"

namespace relief::render {

class CpuLayerProcessing {
 public:
  struct Key {
    size_t layer = 0;
    geo::TileKey tile;
    uint32_t version = 0;
    auto operator<=>(const Key&) const = default;
  };
  struct Job {
    gpuprocess::OperatorChain chain;  // for the tile's level
    lod::TilePtr tile;                // with its overlap border
    int border = 0;
    process::GlobalStats stats;
    // Set when the layer alone makes the composite: the result is its
    // premultiplied RGBA8 colours (gpuprocess::map_colours_cpu), not values.
    struct Colours {
      float range_min = 0, range_max = 1;
      gpuprocess::ColorMap map = gpuprocess::ColorMap::grey;
      float opacity = 1;
    };
    std::optional<Colours> colours;
    double priority = 0;  // higher first
    uint64_t frame = 0;   // the last frame that asked for it (begin_frame)
  };

  // 0 threads: one per core. `on_done` (may be null) is called on a worker,
  // outside the lock, after each result it stored (a waiting viewer wakes).
  explicit CpuLayerProcessing(unsigned threads, std::function<void()> on_done = nullptr);
  ~CpuLayerProcessing();  // drops the queue, joins
  CpuLayerProcessing(const CpuLayerProcessing&) = delete;
  CpuLayerProcessing& operator=(const CpuLayerProcessing&) = delete;

  // The processed tile (interior plus a one-sample border) of `key` when a
  // worker has finished it; an error when the chain failed; null while it
  // waits or runs, after submitting `job` if it was not yet.
  Result<lod::TilePtr> get_or_submit(const Key& key, Job job);
  // Forgets a result taken (its composite is cached).
  void forget(const Key& key);

  // Forgets queued jobs and results of versions before `version`.
  void drop_before(uint32_t version);

  // Blocks until no job is queued or running, or `seconds` have passed
  // (infinity: until idle); returns whether idle.
  bool wait_idle(double seconds);
  // Seconds the queued and running jobs should take the workers, from the
  // jobs finished so far (0 before the first).
  double estimated_seconds();

  // A new frame: jobs the previous frame did not ask for again (quads out
  // of view) are dropped from the queue.
  void begin_frame();

  // Finished results kept at most (those never taken, e.g. an ancestor's
  // while its children's composites were made first); the oldest go first.
  static constexpr size_t kMaxResults = 64;

 private:
  void work();

  std::mutex mutex_;
  std::condition_variable wake_, finished_cv_;
  bool stopping_ = false;
  uint32_t latest_version_ = 0;  // results of older versions are dropped
  struct Done {
    Result<lod::TilePtr> result;  // null: running
    uint64_t order = 0;           // of finishing
  };
  std::map<Key, Job> queued_;
  std::map<Key, Done> done_;
  uint64_t frame_ = 0, finished_ = 0;
  double job_seconds_ = 0;  // a running mean of a job's seconds
  std::function<void()> on_done_;
  std::vector<std::jthread> threads_;
};

}  // namespace relief::render
