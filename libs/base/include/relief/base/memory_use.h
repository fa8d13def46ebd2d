#pragma once
// The memory this process uses, for per-frame statistics and budget tests.
#include <cstdint>

namespace relief {

// Resident set size in bytes (Linux /proc/self/statm), 0 if unknown.
uint64_t resident_set_bytes();
// Physical memory of the machine in bytes, 0 if unknown.
uint64_t physical_memory_bytes();

}  // namespace relief
