#pragma once
// Time is injected through this interface, like file and network access: the
// frame loop's pacing, the loader's retry pauses and a simulated link's
// latency read and wait on a Clock. The apps pass the steady clock; tests pass
// a ManualClock (manual_clock.h) and decide when time moves, so they assert
// on what happened (which load had answered when a frame was drawn), never on
// how long it took.
#include <chrono>

namespace relief {

class Clock {
 public:
  using Duration = std::chrono::steady_clock::duration;
  using TimePoint = std::chrono::steady_clock::time_point;
  virtual ~Clock() = default;
  virtual TimePoint now() const = 0;
  // Returns once now() >= t. Safe to call from any thread.
  virtual void sleep_until(TimePoint t) const = 0;
};

// std::chrono::steady_clock: real time, for the apps.
const Clock& steady_clock();

// Seconds between two time points, as a double.
inline double seconds_between(Clock::TimePoint from, Clock::TimePoint to) {
  return std::chrono::duration<double>(to - from).count();
}

}  // namespace relief
