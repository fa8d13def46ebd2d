#include "memory_governor.h"

#include <algorithm>

namespace relief::ingest {

namespace {
// The mark sits this far under the budget: a task allocates a few MiB per
// worker between two checks (a bordered tile, its encoding, a warp window).
uint64_t margin_for(uint64_t budget) {
  return std::max<uint64_t>(budget / 16, uint64_t{4} << 20);
}
}  // namespace

MemoryGovernor::MemoryGovernor(uint64_t budget_bytes, Hooks hooks)
    : mark_(budget_bytes - std::min(budget_bytes, margin_for(budget_bytes))),
      hooks_(std::move(hooks)) {}

Status MemoryGovernor::check() {
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock) return {};  // another worker is acting on it
  uint64_t resident = hooks_.resident();
  if (resident == 0 || resident <= mark_) return {};  // 0: unknown
  if (hooks_.release) {
    hooks_.release();
    ++releases_;
    resident = hooks_.resident();
    if (resident <= mark_) return {};
  }
  const uint64_t excess = resident - mark_;
  shrunk_ += excess;
  return hooks_.shrink(excess);
}

uint64_t MemoryGovernor::releases() const {
  std::lock_guard lock(mutex_);
  return releases_;
}

uint64_t MemoryGovernor::shrunk_bytes() const {
  std::lock_guard lock(mutex_);
  return shrunk_;
}

}  // namespace relief::ingest
