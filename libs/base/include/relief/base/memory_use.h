#pragma once
// The memory this process uses, for per-frame statistics and budget tests.
#include <cstdint>

namespace relief {

// Resident set size in bytes (Linux /proc/self/statm), 0 if unknown.
uint64_t resident_set_bytes();

}  // namespace relief
