#pragma once
// Which malloc the relief executable runs on (allocator.cpp, docs/building.md,
// "Allocator"): printed by `relief --version`.
#include <cstdint>
#include <string>

namespace relief::cli {

// "jemalloc <version> (transparent huge pages: <mode>)" or "system malloc".
std::string allocator_description();

// Called with a command's --memory budget before its work starts. Under a
// small budget the process gives up transparent huge pages: they round the
// allocator's partly used memory up to 2 MiB pages (about 12 MiB more peak
// for `relief build --memory 128MiB` on two SRTM tiles, measured), which a
// small budget cannot spare, while their gain (fewer page faults) matters
// only for builds large enough to be given a large budget. glibc's malloc
// (a build without jemalloc) is also held to two arenas there.
void fit_allocator_to_budget(uint64_t budget_bytes);

// The same for a long-running server (`relief serve`): its allocations are
// small and many threads' arenas would each grow in 2 MiB steps, memory a
// server should give back rather than keep (tests/soak: flat memory over
// 130 000 requests).
void give_up_huge_pages();

}  // namespace relief::cli
