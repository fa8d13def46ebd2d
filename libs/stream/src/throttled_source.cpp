#include "relief/stream/throttled_source.h"

#include <mutex>
#include <thread>

namespace relief::stream {

namespace {

using Clock = std::chrono::steady_clock;

class ThrottledSource final : public tiles::StoreSource {
 public:
  ThrottledSource(std::shared_ptr<const tiles::StoreSource> inner, const LinkModel& link)
      : inner_(std::move(inner)), link_(link) {}

  std::string name() const override { return inner_->name(); }

  Result<std::vector<std::byte>> fetch(const std::string& relative) const override {
    const auto start = Clock::now();
    auto bytes = inner_->fetch(relative);
    const uint64_t size = bytes ? bytes->size() : 0;
    // The first byte arrives after the latency; the body then waits for its
    // turn on the shared link.
    Clock::time_point done = start + link_.latency;
    if (link_.bits_per_second > 0) {
      std::lock_guard lock(mutex_);
      const auto begin = std::max(done, link_free_);
      link_free_ =
          begin + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                      static_cast<double>(size) * 8 / link_.bits_per_second));
      done = link_free_;
    }
    std::this_thread::sleep_until(done);
    return bytes;
  }

 private:
  std::shared_ptr<const tiles::StoreSource> inner_;
  LinkModel link_;
  mutable std::mutex mutex_;
  mutable Clock::time_point link_free_{};
};

}  // namespace

std::shared_ptr<const tiles::StoreSource> throttled_source(
    std::shared_ptr<const tiles::StoreSource> inner, const LinkModel& link) {
  return std::make_shared<ThrottledSource>(std::move(inner), link);
}

std::chrono::duration<double> transfer_time(const LinkModel& link, uint64_t bytes) {
  return std::chrono::duration<double>(link.latency) +
         std::chrono::duration<double>(link.bits_per_second > 0
                                           ? static_cast<double>(bytes) * 8 / link.bits_per_second
                                           : 0.0);
}

}  // namespace relief::stream
