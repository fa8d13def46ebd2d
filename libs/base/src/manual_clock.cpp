#include "relief/base/manual_clock.h"

namespace relief {

Clock::TimePoint ManualClock::now() const {
  std::lock_guard lock(mutex_);
  return now_;
}

void ManualClock::sleep_until(TimePoint t) const {
  std::unique_lock lock(mutex_);
  if (free_ && t > now_) {
    now_ = t;
    changed_.notify_all();
  }
  if (now_ >= t) return;
  ++sleepers_;
  changed_.notify_all();
  changed_.wait(lock, [&] { return free_ || now_ >= t; });
  if (now_ < t) now_ = t;  // set free while asleep
  --sleepers_;
  changed_.notify_all();
}

void ManualClock::advance(Duration d) {
  {
    std::lock_guard lock(mutex_);
    now_ += d;
  }
  changed_.notify_all();
}

void ManualClock::set_free(bool free) {
  {
    std::lock_guard lock(mutex_);
    free_ = free;
  }
  changed_.notify_all();
}

size_t ManualClock::sleepers() const {
  std::lock_guard lock(mutex_);
  return sleepers_;
}

bool ManualClock::wait_for_sleepers(size_t n) const {
  std::unique_lock lock(mutex_);
  // Real time, only so that a broken test fails instead of hanging.
  return changed_.wait_for(lock, std::chrono::seconds(60), [&] { return sleepers_ >= n; });
}

}  // namespace relief
