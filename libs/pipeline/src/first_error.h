#pragma once
#include <mutex>
#include <optional>

#include "relief/base/result.h"

namespace relief::pipeline {

// The first error of a parallel loop; later ones are dropped.
class FirstError {
 public:
  void record(const Error& e) {
    std::lock_guard lock(mutex_);
    if (!error_) error_ = e;
  }
  bool failed() {
    std::lock_guard lock(mutex_);
    return error_.has_value();
  }
  Status status() const { return error_ ? Status(std::unexpected(*error_)) : Status{}; }

 private:
  std::mutex mutex_;
  std::optional<Error> error_;
};

}  // namespace relief::pipeline
