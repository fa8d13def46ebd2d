#pragma once
// The lifecycle of one tile in the memory cache (L2), as an explicit state
// machine:
//
//   (absent) --request--> Queued --worker--> Loading --ok--> Resident
//      ^                    |                   |               |
//      +----cancelled-------+                   +--error--> Failed
//      +------------------evicted---------------------------+   |
//      +---------------retry after a pause--------------------+
//
// Every transition is reported as an event; absent tiles have no entry.
#include <cstdint>
#include <string>

#include "relief/geo/tile_key.h"

namespace relief::stream {

enum class TileState : uint8_t { Absent, Queued, Loading, Resident, Failed };

enum class TileEventKind : uint8_t {
  Requested,  // Absent -> Queued
  Cancelled,  // Queued -> Absent: no frame wants it any more
  Started,    // Queued -> Loading
  Loaded,     // Loading -> Resident
  Failed,     // Loading -> Failed
  Evicted,    // Resident -> Absent (budget), or Failed -> Absent (retry allowed)
};

struct TileEvent {
  TileEventKind kind;
  geo::TileKey key;
  uint64_t bytes = 0;  // Loaded/Evicted: decoded bytes
  bool prefetch = false;
  std::string error;  // Failed
};

// Whether the state machine has this edge (asserted on every transition).
constexpr bool allowed(TileState from, TileState to) {
  switch (from) {
    case TileState::Absent:
      return to == TileState::Queued;
    case TileState::Queued:
      return to == TileState::Loading || to == TileState::Absent;
    case TileState::Loading:
      return to == TileState::Resident || to == TileState::Failed;
    case TileState::Resident:
      return to == TileState::Absent;
    case TileState::Failed:
      return to == TileState::Absent;
  }
  return false;
}

const char* to_string(TileState s);
const char* to_string(TileEventKind k);

}  // namespace relief::stream
