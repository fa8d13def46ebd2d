#pragma once
// Which malloc the relief executable runs on (allocator.cpp, docs/building.md,
// "Allocator"): printed by `relief --version`.
#include <string>

namespace relief::cli {

// "jemalloc <version> (transparent huge pages: <mode>)" or "system malloc".
std::string allocator_description();

}  // namespace relief::cli
