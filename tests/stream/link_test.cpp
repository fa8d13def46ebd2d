// The manual test clock and the simulated link (stream::throttled_source) on
// it: requests overlap their latency, bodies take turns on the bandwidth.
// Every step is decided by the test moving the clock, not by this machine's
// speed.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <thread>

#include "relief/base/manual_clock.h"
#include "relief/stream/throttled_source.h"
#include "test_support.h"

namespace relief::testing {
namespace {

using namespace std::chrono_literals;

// Waits (in real time, only as a safety net) until `done` holds.
template <typename F>
bool eventually(F done) {
  for (int i = 0; i < 60000 && !done(); ++i) std::this_thread::sleep_for(1ms);
  return done();
}

TEST(ManualClock, SleepersWakeOnlyOnceTimePassesTheirDeadline) {
  ManualClock clock;
  const auto t0 = clock.now();
  std::atomic<bool> woke{false};
  std::thread sleeper([&] {
    clock.sleep_until(t0 + 1s);
    woke = true;
  });
  ASSERT_TRUE(clock.wait_for_sleepers(1));
  clock.advance(999ms);
  EXPECT_FALSE(woke);
  EXPECT_EQ(clock.sleepers(), 1u);
  clock.advance(1ms);
  sleeper.join();
  EXPECT_TRUE(woke);
  EXPECT_EQ(clock.sleepers(), 0u);
  EXPECT_EQ(clock.now(), t0 + 1s);
  clock.sleep_until(t0);  // a deadline already past returns at once
  // Free, time jumps to each deadline instead of waiting.
  clock.set_free(true);
  clock.sleep_until(t0 + 5s);
  EXPECT_EQ(clock.now(), t0 + 5s);
}

TEST(SimulatedLink, RequestsOverlapTheirLatencyAndShareTheBandwidth) {
  ScratchDir dir("simulated_link");
  std::ofstream(dir / "a.bin", std::ios::binary) << std::string(1000, 'x');
  ManualClock clock;
  // 50 ms latency; 1000 bytes take 100 ms of an 80 kbit/s link.
  const stream::LinkModel model{50ms, 80e3};
  EXPECT_DOUBLE_EQ(stream::transfer_time(model, 1000).count(), 0.15);
  auto link = stream::throttled_source(tiles::local_source(dir.path()), model, clock);
  std::atomic<int> answered{0};
  std::vector<std::thread> requests;
  for (int i = 0; i < 2; ++i) {
    requests.emplace_back([&] {
      auto bytes = link->fetch("a.bin");
      EXPECT_TRUE(bytes && bytes->size() == 1000);
      ++answered;
    });
  }
  ASSERT_TRUE(clock.wait_for_sleepers(2));
  // Both wait out the latency at once; then the first body, then the second.
  clock.advance(150ms - 1us);
  EXPECT_EQ(answered, 0);
  clock.advance(1us);
  EXPECT_TRUE(eventually([&] { return answered == 1; }));
  clock.advance(100ms - 1us);
  EXPECT_EQ(answered, 1);
  clock.advance(1us);
  for (auto& t : requests) t.join();
  EXPECT_EQ(answered, 2);
}

}  // namespace
}  // namespace relief::testing
