#pragma once
// Failures on input are values, not exceptions: every fallible function returns
// Result<T>, whose error message names the file or argument and the problem.
#include <expected>
#include <string>
#include <utility>

namespace relief {

struct Error {
  std::string message;
};

template <class T>
using Result = std::expected<T, Error>;

using Status = std::expected<void, Error>;

inline std::unexpected<Error> fail(std::string message) {
  return std::unexpected<Error>(Error{std::move(message)});
}

}  // namespace relief

// Propagates the error of an expression returning Result/Status; yields its value.
#define RELIEF_TRY(expr)                                                         \
  ({                                                                             \
    auto relief_try_result_ = (expr);                                            \
    if (!relief_try_result_) return std::unexpected(relief_try_result_.error()); \
    std::move(*relief_try_result_);                                              \
  })

#define RELIEF_CHECK(expr)                                                           \
  do {                                                                               \
    auto relief_check_status_ = (expr);                                              \
    if (!relief_check_status_) return std::unexpected(relief_check_status_.error()); \
  } while (0)
