// Fuzz target: a level index (<level>/index.rli). Parsing must fail with a
// message or give an index that serialises and parses back to the same tiles.
// Each input is parsed as it is and with its trailing CRC-32 recomputed, so
// mutations reach the fields behind the checksum.
#include <cstring>
#include <span>
#include <vector>

#include "fuzz_check.h"
#include "relief/tiles/level_index.h"
#include "relief/tiles/tile_file.h"

namespace {

using namespace relief::tiles;

void parse_and_check(std::span<const std::byte> bytes) {
  auto index = LevelIndex::parse(bytes, "fuzz.rli");
  if (!index) {
    FUZZ_CHECK(index.error().message.starts_with("fuzz.rli: "));
    return;
  }
  for (const IndexEntry& e : index->entries()) {
    FUZZ_CHECK(e.key.valid() && e.key.level == index->level());
    FUZZ_CHECK(index->find(e.key) == &e);
  }
  auto again = LevelIndex::parse(index->serialize(), "again.rli");
  FUZZ_CHECK(again.has_value());
  FUZZ_CHECK(again->level() == index->level() && again->size() == index->size());
  for (size_t i = 0; i < index->size(); ++i) {
    FUZZ_CHECK(again->entries()[i].key == index->entries()[i].key);
    FUZZ_CHECK(again->entries()[i].error == index->entries()[i].error);
  }
}

// `relief upgrade`'s reader: version 1 or 2, the same guarantees.
void parse_old_and_check(std::span<const std::byte> bytes) {
  auto index = LevelIndex::parse_for_upgrade(bytes, "old.rli");
  if (!index) {
    FUZZ_CHECK(index.error().message.starts_with("old.rli: "));
    return;
  }
  for (const IndexEntry& e : index->entries()) {
    FUZZ_CHECK(e.key.valid() && e.key.level == index->level() && e.error >= 0);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto bytes = std::as_bytes(std::span(data, size));
  parse_and_check(bytes);
  parse_old_and_check(bytes);
  if (size < 4) return 0;
  std::vector<std::byte> fixed(bytes.begin(), bytes.end());
  const uint32_t crc = crc32_of(std::span(fixed).first(size - 4));
  std::memcpy(fixed.data() + size - 4, &crc, sizeof crc);
  parse_and_check(fixed);
  parse_old_and_check(fixed);
  return 0;
}
