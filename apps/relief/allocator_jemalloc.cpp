// The relief executable links jemalloc (RELIEF_JEMALLOC, docs/building.md,
// "Allocator") for what the frame loop asks of its heap: freed memory kept
// (keep_freed_memory), the frames' heap faulted in before the first frame
// (prefault_frame_heap) and blocks faulted in ahead on a helper thread in
// the render thread's arena (prefault_in_background).
//
// The page size is left to the system (thp:default: huge pages only where
// the kernel gives them to all memory). Asking for 2 MiB pages always (the
// setting until 2026-12-06) made a still of the Himalaya block 2.4-3.8x slower
// and its build 1.5-1.6x on this project's virtual machines, whose host backs
// a fresh huge page slowly (bench/allocator). On 4 KiB pages two settings
// keep the frames' heap faulted in: a free block of any size may serve a
// small request (lg_extent_max_active_fit: jemalloc's default lets a free
// block serve a request at most 64 times smaller, so the 1 MiB blocks of
// prefault_frame_heap never served the frames' small slabs, which took
// fresh pages frame after frame), and jemalloc's own metadata, a few MiB,
// stays on huge pages. MALLOC_CONF still overrides it all.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdlib>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <pthread.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fmt/format.h>
#include <jemalloc/jemalloc.h>

#include "allocator.h"

// jemalloc looks this symbol up by name when it starts.
extern "C" const char* malloc_conf;
const char* malloc_conf = "thp:default,metadata_thp:always,lg_extent_max_active_fit:12";

namespace relief::cli {

std::string allocator_description() {
  const char* version = "?";
  const char* thp = "?";
  size_t size = sizeof(const char*);
  mallctl("version", static_cast<void*>(&version), &size, nullptr, 0);
  size = sizeof(const char*);
  mallctl("opt.thp", static_cast<void*>(&thp), &size, nullptr, 0);
  ssize_t decay = 0;
  size = sizeof decay;
  const bool kept = mallctl("arena.0.dirty_decay_ms", &decay, &size, nullptr, 0) == 0 && decay < 0;
  return fmt::format("jemalloc {} (transparent huge pages: {}{}{})", version, thp,
                     kept ? "; freed memory kept" : "", prefault_note());
}

namespace {

// The helper thread of prefault_in_background(). The blocks asked while it
// works are freed together: a block freed before the next is allocated
// would be that block again (and jemalloc does not serve two blocks from
// the halves of one freed twice as large, measured). Each is a quarter
// larger than asked: a driver pads texture rows and columns (llvmpipe:
// widths to 4 texels and rows to 64 bytes, heights to 4 rows; 146 x 82
// R32F layers take 12 % more), and a smaller free block would not serve it.
class Prefaulter {
  static constexpr uint64_t kPiece = uint64_t{1} << 20;

 public:
  ~Prefaulter() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_one();
    if (thread_.joinable()) thread_.join();
  }

  // On the thread that will allocate the block: blocks under 8 MiB come
  // from that thread's arena, which the helper then uses too.
  void request(uint64_t bytes) {
    unsigned arena = 0;
    size_t size = sizeof arena;
    if (mallctl("thread.arena", &arena, &size, nullptr, 0) != 0) return;
    {
      std::lock_guard lock(mutex_);
      queue_.push_back({bytes, arena});
      if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
    }
    wake_.notify_one();
  }

 private:
  void run() {
    pthread_setname_np(pthread_self(), "relief-prefault");
    setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10);  // below the render thread
    std::unique_lock lock(mutex_);
    std::vector<void*> held;
    while (true) {
      if (queue_.empty()) {
        for (void* p : held) std::free(p);
        held.clear();
      }
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      const auto [bytes, arena] = queue_.front();
      queue_.pop_front();
      lock.unlock();
      unsigned own = arena;
      mallctl("thread.arena", nullptr, nullptr, &own, sizeof own);
      const uint64_t padded = bytes + bytes / 4;
      if (void* p = std::malloc(padded)) {
        // In 1 MiB pieces: stopping (exit) need not wait for the rest.
        for (uint64_t at = 0; at < padded && !stop_; at += kPiece) {
          touch_pages(static_cast<char*>(p) + at, std::min(kPiece, padded - at));
        }
        held.push_back(p);
      }
      lock.lock();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  struct Block {
    uint64_t bytes;
    unsigned arena;
  };
  std::deque<Block> queue_;
  std::atomic<bool> stop_ = false;  // also read while touching: exit need not wait
  std::thread thread_;
};

}  // namespace

void prefault_in_background(uint64_t bytes) {
  static Prefaulter prefaulter;
  prefaulter.request(bytes);
}

void keep_freed_memory() {
  // Only where the frames' buffers live: the calling (render) thread's arena,
  // and the one arena every block over 8 MiB comes from (texture arrays and
  // their prefaulted growth). The loaders' threads free what they decoded
  // as tiles leave the caches; their arenas return it to the kernel after
  // jemalloc's decay, so the process stays near its caches' budget.
  ssize_t never = -1;
  const auto keep = [&never](unsigned arena) {
    for (const char* kind : {"dirty", "muzzy"}) {
      const std::string name = fmt::format("arena.{}.{}_decay_ms", arena, kind);
      mallctl(name.c_str(), nullptr, nullptr, &never, sizeof never);
    }
  };
  unsigned arena = 0;
  size_t size = sizeof arena;
  if (mallctl("thread.arena", &arena, &size, nullptr, 0) == 0) keep(arena);
  constexpr size_t kLarge = size_t{16} << 20;
  if (void* large = std::malloc(kLarge)) {
    size = sizeof arena;
    if (mallctl("arenas.lookup", &arena, &size, &large, sizeof large) == 0) keep(arena);
    std::free(large);
  }
}

void release_freed_memory() {
  // Every arena at once: MALLCTL_ARENAS_ALL.
  const std::string name = fmt::format("arena.{}.purge", MALLCTL_ARENAS_ALL);
  mallctl(name.c_str(), nullptr, nullptr, nullptr, 0);
}

}  // namespace relief::cli
