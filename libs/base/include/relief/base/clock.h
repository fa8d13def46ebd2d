#pragma once
// Time is injected through this interface, like file and network access: the
// frame loop's pacing, the loader's retry pauses and a simulated link's
// latency read and wait on a Clock. The apps pass the steady clock; tests pass
// a ManualClock and decide when time moves, so they assert on what happened
// (which load had answered when a frame was drawn), never on how long it took.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>

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

// A clock for tests: time stands still until the test advances it; sleepers
// wake when it passes their deadline. The test can wait until a number of
// threads are asleep on it (for instance every load of a slow source in
// flight), so every step is deterministic.
class ManualClock final : public Clock {
 public:
  TimePoint now() const override;
  void sleep_until(TimePoint t) const override;

  void advance(Duration d);
  // While free, time jumps to each sleeper's deadline at once instead of
  // waiting for the test (a simulation that runs as fast as it can: to let
  // the loads of a test finish, and before its loaders are destroyed).
  void set_free(bool free);
  // Threads asleep in sleep_until() right now.
  size_t sleepers() const;
  // Waits until at least `n` threads are asleep (false after a generous real
  // timeout: a test failure rather than a hang).
  bool wait_for_sleepers(size_t n) const;

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  mutable TimePoint now_{};  // starts at the steady clock's epoch; sleepers move it when free
  bool free_ = false;
  mutable size_t sleepers_ = 0;
};

}  // namespace relief
