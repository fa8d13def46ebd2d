// Fuzz target: manifest.json. Parsing must fail with a message or give a
// manifest whose own JSON parses back to the same description.
#include <string>

#include "fuzz_check.h"
#include "relief/tiles/manifest.h"

using namespace relief::tiles;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto manifest = Manifest::from_json(text, "fuzz.json");
  if (!manifest) {
    FUZZ_CHECK(manifest.error().message.starts_with("fuzz.json: "));
    return 0;
  }
  auto again = Manifest::from_json(manifest->to_json(), "again.json");
  FUZZ_CHECK(again.has_value());
  FUZZ_CHECK(again->to_json() == manifest->to_json());
  return 0;
}
