#pragma once
// The scene the window tests draw: the Pyrenees store, an oblique view over
// it as --look-at values, and the window's size.
#include <string>

#include "../ingest/built_stores.h"

namespace relief::window {

inline constexpr int kWidth = 320, kHeight = 240;
// An oblique view over the Pyrenees, as `relief view --look-at` values.
inline constexpr const char* kLookAt = "1.5,42.5,1500,30000,20,-35";

inline std::string store_path() {
  return testing::pyrenees_store().root().string();
}

}  // namespace relief::window
