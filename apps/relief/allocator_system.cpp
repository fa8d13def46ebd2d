// The relief executable without jemalloc (RELIEF_JEMALLOC off, jemalloc not
// found, or a sanitizer build, whose runtime replaces malloc).
#include <malloc.h>

#include "allocator.h"

namespace relief::cli {

std::string allocator_description() {
  const std::string note = prefault_note();
  return note.empty() ? "system malloc" : "system malloc (" + note.substr(2) + ")";
}

void keep_freed_memory() {
  // glibc's malloc maps large blocks apart and unmaps them when freed, and
  // trims the heap's free top: a frame's buffers would come back as fresh
  // pages. (No-ops under a sanitizer's allocator.)
  ::mallopt(M_MMAP_THRESHOLD, 32 << 20);
  ::mallopt(M_TRIM_THRESHOLD, 256 << 20);
}

void prefault_in_background(uint64_t) {}

void release_freed_memory() {
  ::malloc_trim(0);
}

}  // namespace relief::cli
