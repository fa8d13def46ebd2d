#pragma once
// Which malloc the relief executable runs on (allocator.cpp, docs/building.md,
// "Allocator"): printed by `relief --version`.
#include <cstdint>
#include <string>

namespace relief::cli {

// "jemalloc <version> (transparent huge pages: <mode>)", with "; freed
// memory kept" after keep_freed_memory(), or "system malloc"; then
// prefault_note().
std::string allocator_description();

// Called with a command's --memory budget before its work starts. Under a
// small budget the process gives up transparent huge pages: they round the
// allocator's partly used memory up to 2 MiB pages (about 12 MiB more peak
// for `relief build --memory 128MiB` on two SRTM tiles, measured), which a
// small budget cannot spare, while their gain (fewer page faults) matters
// only for builds large enough to be given a large budget. glibc's malloc
// (a build without jemalloc) is also held to two arenas there.
void fit_allocator_to_budget(uint64_t budget_bytes);

// Hands the pages of freed memory the allocator still holds back to the
// system now (jemalloc keeps them for seconds; glibc's malloc keeps the free
// top of its heaps). For a command whose resident memory nears its --memory
// budget (ingest's MemoryGovernor): those pages count in it.
void release_freed_memory();

// The same for a long-running server (`relief serve`): its allocations are
// small and many threads' arenas would each grow in 2 MiB steps, memory a
// server should give back rather than keep (tests/soak: flat memory over
// 130 000 requests).
void give_up_huge_pages();

// For the commands that draw frame after frame (`relief view`, `relief
// render`): memory freed stays with the allocator for the next frame instead
// of going back to the kernel. jemalloc returns freed pages gradually
// (decay), and a frame's buffers freed at its end were among them: every few
// frames the next one faulted them in again, zero-filled (on bench/stream's
// Himalaya flight every tenth frame took 7 ms more refinement and 15 ms more
// in all, the p99 frame 1.55 times the p50 instead of 1.37). Only the calling
// (render) thread's arena and the one serving blocks over 8 MiB: the loaders'
// threads free evicted tiles, which their arenas return after the decay (a
// long flight's resident memory stayed 1.04 GiB under a 256 MiB budget when
// every arena kept them, 0.69-0.78 GiB so). Overrides MALLOC_CONF's decay
// settings for those two arenas.
void keep_freed_memory();

// For the same commands, on the thread that will draw the frames, after
// keep_freed_memory(): touches `bytes` of that thread's heap now and frees
// it, kept, so that the frames' buffers, as they grow to their peak, reuse
// pages already in memory instead of faulting in fresh ones mid-flight. On
// this project's virtual machines the host backs a page at its first touch
// (7-13 us per 4 KiB page, a few ms per 2 MiB huge page): on bench/stream's
// Himalaya flight the frames that took even one fault were among the
// slowest, and 64 MiB made p99/p50 1.29-1.39 instead of 1.49-1.53
// (docs/building.md, "Allocator"). The memory stays the process's.
void prefault_frame_heap(uint64_t bytes);
constexpr uint64_t kFrameHeapBytes = uint64_t{64} << 20;
// The same for a block of `bytes` that the render thread will allocate soon
// (a texture array's next growth: TerrainRenderer::set_on_growth_ahead):
// faulted in and freed on a helper thread of low priority, so that the
// allocation finds it in memory (jemalloc serves every block over 8 MiB
// from one arena, whatever the thread, and keeps it after
// keep_freed_memory()). A no-op without jemalloc (glibc's malloc maps
// blocks over 32 MiB apart and unmaps them when freed, and keeps smaller
// ones in the arena of the thread that freed them). The growth of
// an imagery array from 128 to 256 layers took 0.57-0.69 s of one frame of
// bench/view's Himalaya flight, nearly all of it the fresh pages.
void prefault_in_background(uint64_t bytes);

// Writes one byte in every page of `bytes` at `p`, so that the kernel maps
// them all now (for the two functions above).
void touch_pages(void* p, uint64_t bytes);

// "; N MiB of heap faulted in" after prefault_frame_heap(), else "" (for
// allocator_description()).
std::string prefault_note();

}  // namespace relief::cli
