#pragma once
// A store source that behaves like a slow network in front of another source:
// every request waits `latency` (requests in parallel overlap), and the bytes
// of all requests share one link of `bits_per_second`. For tests and
// benchmarks of streaming (and `relief render --simulate-latency`): the real
// loopback servers answer too fast to show what latency does.
//
// The waits are on `clock`: with a ManualClock a test decides when each
// answer arrives (a fetch returns once the test advanced the clock past its
// time), so it can check what a frame drew while the source had not answered.
#include <chrono>
#include <memory>

#include "relief/base/clock.h"
#include "relief/tiles/store_source.h"

namespace relief::stream {

struct LinkModel {
  std::chrono::microseconds latency{0};
  double bits_per_second = 0;  // 0: unlimited
};

// `clock` must outlive the source.
std::shared_ptr<const tiles::StoreSource> throttled_source(
    std::shared_ptr<const tiles::StoreSource> inner, const LinkModel& link,
    const Clock& clock = steady_clock());

// The time the link needs for one request of `bytes` when alone on it.
std::chrono::duration<double> transfer_time(const LinkModel& link, uint64_t bytes);

}  // namespace relief::stream
