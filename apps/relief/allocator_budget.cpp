// Transparent huge pages under a small --memory budget (allocator.h). The
// kernel's per-process switch applies whatever the allocator asked for with
// madvise, so one function serves jemalloc and the system malloc alike.
#include <sys/prctl.h>

#include "allocator.h"

namespace relief::cli {

namespace {
constexpr uint64_t kSmallBudget = uint64_t{512} << 20;
}

void give_up_huge_pages() {
  // Pages already huge stay huge; the ones touched from here on do not.
  ::prctl(PR_SET_THP_DISABLE, 1, 0, 0, 0);
}

void fit_allocator_to_budget(uint64_t budget_bytes) {
  if (budget_bytes < kSmallBudget) give_up_huge_pages();
}

}  // namespace relief::cli
