// The relief executable links jemalloc (RELIEF_JEMALLOC, docs/building.md,
// "Allocator"). A build touches about as many fresh pages as its peak
// resident size, and on this project's virtual machines each 4 KiB page
// fault is expensive: with transparent huge pages the same bytes take about
// a thirtieth of the faults, and `relief build` a sixth less CPU time.
// glibc's malloc can do the same only through an environment variable read
// at start-up (GLIBC_TUNABLES=glibc.malloc.hugetlb=1); jemalloc reads this
// symbol, so the choice is part of the program, not of its environment
// (MALLOC_CONF still overrides it).
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
const char* malloc_conf = "thp:always,metadata_thp:auto";

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
  ssize_t never = -1;
  for (const char* name : {"arenas.dirty_decay_ms", "arenas.muzzy_decay_ms"}) {  // arenas to come
    mallctl(name, nullptr, nullptr, &never, sizeof never);
  }
  unsigned arenas = 0;
  size_t size = sizeof arenas;
  if (mallctl("arenas.narenas", &arenas, &size, nullptr, 0) != 0) return;
  // An arena not made yet refuses: it will follow the defaults set above.
  for (unsigned i = 0; i < arenas; ++i) {
    for (const char* kind : {"dirty", "muzzy"}) {
      const std::string name = fmt::format("arena.{}.{}_decay_ms", i, kind);
      mallctl(name.c_str(), nullptr, nullptr, &never, sizeof never);
    }
  }
}

}  // namespace relief::cli
