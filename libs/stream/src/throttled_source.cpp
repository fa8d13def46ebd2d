#include "relief/stream/throttled_source.h"

#include <mutex>

namespace relief::stream {

namespace {

class ThrottledSource final : public tiles::StoreSource {
 public:
  ThrottledSource(std::shared_ptr<const tiles::StoreSource> inner, const LinkModel& link,
                  const Clock& clock)
      : inner_(std::move(inner)), link_(link), clock_(clock) {}

  std::string name() const override { return inner_->name(); }
  bool holds_files() const override { return inner_->holds_files(); }

  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    const auto start = clock_.now();
    auto bytes = inner_->fetch(relative);
    const uint64_t size = bytes ? bytes->size() : 0;
    // The first byte arrives after the latency; the body then waits for its
    // turn on the shared link.
    Clock::TimePoint done = start + link_.latency;
    if (link_.bits_per_second > 0) {
      std::lock_guard lock(mutex_);
      const auto begin = std::max(done, link_free_);
      link_free_ =
          begin + std::chrono::duration_cast<Clock::Duration>(std::chrono::duration<double>(
                      static_cast<double>(size) * 8 / link_.bits_per_second));
      done = link_free_;
    }
    clock_.sleep_until(done);
    return bytes;
  }

 private:
  std::shared_ptr<const tiles::StoreSource> inner_;
  LinkModel link_;
  const Clock& clock_;
  mutable std::mutex mutex_;
  mutable Clock::TimePoint link_free_{};
};

}  // namespace

std::shared_ptr<const tiles::StoreSource> throttled_source(
    std::shared_ptr<const tiles::StoreSource> inner, const LinkModel& link, const Clock& clock) {
  return std::make_shared<ThrottledSource>(std::move(inner), link, clock);
}

std::chrono::duration<double> transfer_time(const LinkModel& link, uint64_t bytes) {
  return std::chrono::duration<double>(link.latency) +
         std::chrono::duration<double>(link.bits_per_second > 0
                                           ? static_cast<double>(bytes) * 8 / link.bits_per_second
                                           : 0.0);
}

}  // namespace relief::stream
