#pragma once
// A Clock for tests: time stands still until the test moves it.
#include <condition_variable>
#include <cstddef>
#include <mutex>

#include "relief/base/clock.h"

namespace relief {

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
