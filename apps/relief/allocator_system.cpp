// The relief executable without jemalloc (RELIEF_JEMALLOC off, jemalloc not
// found, or a sanitizer build, whose runtime replaces malloc).
#include "allocator.h"

namespace relief::cli {

std::string allocator_description() {
  return "system malloc";
}

}  // namespace relief::cli
