#pragma once
// The memory cache (L2) of decoded tiles of one store (elevation heights or
// imagery) and the asynchronous loader that fills it, as a non-blocking
// lod::TileProvider.
//
// Threads: the render thread calls everything here; worker threads (as many
// as loads may be in flight) read and decode tiles. Event listeners run on
// the render thread, in begin_frame(). The workers are named
// "relief-loader" and may run at a lower CPU priority
// (LoaderOptions::worker_nice; off by default, the option says why). A
// worker that ends a load calls LoaderOptions::on_settled (a viewer waiting
// for tiles wakes up).
//
// Priority: each frame's requests (from selection, with view priorities)
// replace the previous frame's queue; queued tiles no frame wants any more are
// cancelled. Ancestors come first by construction: selection requests a
// quad's children only once the quad's own data is resident. Prefetch
// requests (the view predicted along the camera's motion) rank after every
// request of the current view, but may take up to a quarter of the loads in
// flight, so they run even while the current view keeps the link busy.
//
// Budget: resident bytes never exceed the budget. Tiles a caller holds (the
// TilePtr is the pin) and the level-0 tiles (loaded at creation and kept) are
// never evicted; a loaded tile that does not fit beside the pinned ones is
// dropped again.
#include <functional>
#include <memory>
#include <vector>

#include "relief/base/clock.h"
#include "relief/base/result.h"
#include "relief/lod/tile_provider.h"
#include "relief/stream/tile_lifecycle.h"

namespace relief::tiles {
class Store;
}

namespace relief::stream {

struct LoaderOptions {
  int max_in_flight = 8;  // worker threads
  // How many workers may run the Prepare step (the diamond errors: ~10 ms of
  // CPU per elevation tile) at once; 0: all of them. Reads (I/O) are not
  // limited by it. `relief view` sets one less than the cores: on 2 cores,
  // 8 workers preparing at once took the core the render thread needs, and
  // a frame of 25 ms CPU took 100 ms in a turn (docs/streaming.md). Off by
  // default: work that waits for complete frames wants the throughput.
  int max_preparing = 0;
  uint64_t memory_budget = uint64_t{256} << 20;  // resident decoded bytes
  // A failed tile may load again after this pause, doubled after each further
  // failure of the same tile up to retry_failed_max (a dead server is not
  // hammered; a recovered one is used again soon).
  double retry_failed_after = 2.0;  // seconds
  double retry_failed_max = 60.0;   // seconds
  // What the retry pauses are measured on (tests pass a ManualClock); must
  // outlive the loader.
  const Clock* clock = &steady_clock();
  // Added to the workers' nice value (Linux: per thread; capped at 19).
  // 0, the default: the priority of the thread that creates the loader.
  // 10 gave steadier frames under load on 2 cores (the workers take what
  // the render thread and llvmpipe leave), but a render loop that keeps the
  // cores busy while the view is incomplete then starves the loads: under
  // ASan `relief view` did not complete a still view in 30 s. Not the
  // default until the viewer idles while it waits (docs/streaming.md).
  int worker_nice = 0;
  // Called on a worker thread each time a load ends (the tile resident,
  // failed, or dropped again for the budget), after the state change and
  // outside the loader's lock: what a frame draws may have changed. Must be
  // thread-safe, quick, and callable until the loader is destroyed.
  std::function<void()> on_settled = nullptr;
};

struct LevelUse {
  uint32_t tiles = 0;
  uint64_t bytes = 0;
};

struct LoaderStats {
  std::vector<LevelUse> resident_per_level;
  uint32_t resident_tiles = 0;
  uint64_t resident_bytes = 0, memory_budget = 0, pinned_bytes = 0;
  uint32_t queued = 0, in_flight = 0;
  uint64_t hits = 0, misses = 0;  // get() of resident / not resident tiles
  uint64_t requested = 0, loaded = 0, failed = 0, evicted = 0, cancelled = 0;
  uint64_t bytes_fetched = 0;                  // tile file bytes read from the source
  uint64_t prefetched = 0, prefetch_used = 0;  // loaded by prefetch; of those, later drawn
  uint32_t most_preparing = 0;  // the most workers in the Prepare step at once, so far
  uint64_t woken = 0;           // workers end_frame() woke: at most one per tile queued
};

class TileLoader final : public lod::TileProvider {
 public:
  // Loads and keeps the store's level-0 tiles (a blocking read, once).
  static Result<std::unique_ptr<TileLoader>> create(const tiles::Store& store,
                                                    const LoaderOptions& options);
  ~TileLoader() override;

  bool blocking() const override { return false; }
  Result<lod::TilePtr> get(const geo::TileKey& key) override;
  void request(const geo::TileKey& key, double priority) override;
  void begin_frame() override;
  void end_frame() override;
  void set_prepare(Prepare prepare) override;
  // Evicts the tile now, or in the first begin_frame() after its last pin
  // went (an Evicted event); nothing for level 0 or a tile not resident.
  void forget(const geo::TileKey& key) override;

  // While set, requests are prefetch: ranked after the current view's.
  void set_prefetch(bool on) { prefetching_ = on; }

  // Called on the render thread (in begin_frame) for every transition.
  void subscribe(std::function<void(const TileEvent&)> listener);
  LoaderStats stats() const;
  // stats().resident_bytes without the walk over every entry (per frame).
  uint64_t resident_bytes() const;
  TileState state(const geo::TileKey& key) const;
  // Nothing queued or loading, and every load that ended announced
  // (LoaderOptions::on_settled has returned).
  bool idle() const;

 private:
  struct Impl;
  explicit TileLoader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  bool prefetching_ = false;
};

}  // namespace relief::stream
