#pragma once
// The first error raised by any worker of a parallel loop; later ones are
// dropped, and workers check failed() to skip the remaining work.
#include <atomic>
#include <mutex>
#include <optional>

#include "relief/base/result.h"

namespace relief {

class FirstError {
 public:
  void set(Error e) {
    std::lock_guard lock(mutex_);
    if (!error_) error_ = std::move(e);
    failed_ = true;
  }
  bool failed() const { return failed_; }
  // Call after the loop has returned.
  Status status() const {
    if (error_) return std::unexpected(*error_);
    return {};
  }

 private:
  std::mutex mutex_;
  std::optional<Error> error_;
  std::atomic<bool> failed_{false};
};

}  // namespace relief
