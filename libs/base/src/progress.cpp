#include "relief/base/progress.h"

#include <unistd.h>

#include <fmt/format.h>
#include <cstdio>

namespace relief {

void TerminalProgress::begin(std::string stage, uint64_t total) {
  std::lock_guard lock(mutex_);
  stage_ = std::move(stage);
  total_ = total;
  done_ = 0;
  start_ = last_draw_ = std::chrono::steady_clock::now();
  draw(false);
}

void TerminalProgress::advance(uint64_t n) {
  std::lock_guard lock(mutex_);
  done_ += n;
  auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ > std::chrono::milliseconds(100)) {
    last_draw_ = now;
    draw(false);
  }
}

void TerminalProgress::end() {
  std::lock_guard lock(mutex_);
  draw(true);
}

void TerminalProgress::draw(bool final_line) {
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = seconds > 0 ? static_cast<double>(done_) / seconds : 0.0;
  const double fraction = total_ ? static_cast<double>(done_) / static_cast<double>(total_) : 1.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(fraction * kWidth);
  std::string bar(static_cast<size_t>(filled), '#');
  bar.resize(kWidth, '.');
  std::string eta = "--";
  if (rate > 0 && done_ < total_) {
    eta = fmt::format("{:.0f}s", static_cast<double>(total_ - done_) / rate);
  }
  std::fprintf(stderr, "\r%-18s [%s] %llu/%llu  %.1f/s  ETA %s   %s", stage_.c_str(), bar.c_str(),
               static_cast<unsigned long long>(done_), static_cast<unsigned long long>(total_),
               rate, eta.c_str(), final_line ? "\n" : "");
  std::fflush(stderr);
}

std::unique_ptr<Progress> make_progress_for_stderr() {
  if (::isatty(STDERR_FILENO)) return std::make_unique<TerminalProgress>();
  return std::make_unique<NullProgress>();
}

}  // namespace relief
