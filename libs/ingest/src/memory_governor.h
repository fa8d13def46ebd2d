#pragma once
// Holds a build's resident memory under its --memory budget where the plan's
// estimates (build.cpp, plan_memory) fall short: the allocator keeps freed
// pages for a while, cores handed out are still alive after the core cache
// let them go, and libraries allocate what no estimate sees. Between tasks a
// worker compares the resident memory with a mark just under the budget;
// above it, the allocator first hands its freed pages back, and if that is
// not enough the core cache gives up the excess (its cores spilled to disk).
// The Himalaya block under --memory 256MiB peaked at 292 MiB without it.
#include <cstdint>
#include <functional>
#include <mutex>

#include "relief/base/result.h"

namespace relief::ingest {

class MemoryGovernor {
 public:
  struct Hooks {
    std::function<uint64_t()> resident;      // bytes resident now
    std::function<void()> release;           // freed pages back to the system; may be empty
    std::function<Status(uint64_t)> shrink;  // takes this many bytes out of the caches
  };
  MemoryGovernor(uint64_t budget_bytes, Hooks hooks);

  // From any worker, between tasks; a read of the resident size when under
  // the mark. One worker acts at a time, the others go on.
  Status check();

  uint64_t mark() const { return mark_; }
  uint64_t releases() const;
  uint64_t shrunk_bytes() const;

 private:
  uint64_t mark_;
  Hooks hooks_;
  mutable std::mutex mutex_;
  uint64_t releases_ = 0, shrunk_ = 0;
};

}  // namespace relief::ingest
