// The relief executable links jemalloc (RELIEF_JEMALLOC, docs/building.md,
// "Allocator"). A build touches about as many fresh pages as its peak
// resident size, and on this project's virtual machines each 4 KiB page
// fault is expensive: with transparent huge pages the same bytes take about
// a thirtieth of the faults, and `relief build` a sixth less CPU time.
// glibc's malloc can do the same only through an environment variable read
// at start-up (GLIBC_TUNABLES=glibc.malloc.hugetlb=1); jemalloc reads this
// symbol, so the choice is part of the program, not of its environment
// (MALLOC_CONF still overrides it).
#include <cstddef>
#include <string>

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
