#pragma once
// Progress reporting is an interface so libraries never write to the terminal
// themselves; the app decides whether to draw a bar.
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

namespace relief {

class Progress {
 public:
  virtual ~Progress() = default;
  virtual void begin(std::string stage, uint64_t total) = 0;
  virtual void advance(uint64_t n = 1) = 0;
  virtual void end() = 0;
};

class NullProgress final : public Progress {
 public:
  void begin(std::string, uint64_t) override {}
  void advance(uint64_t) override {}
  void end() override {}
};

// A one-line bar on stderr with rate and ETA, redrawn at most ~10 times a second.
class TerminalProgress final : public Progress {
 public:
  void begin(std::string stage, uint64_t total) override;
  void advance(uint64_t n = 1) override;
  void end() override;

 private:
  void draw(bool final_line);
  std::mutex mutex_;
  std::string stage_;
  uint64_t total_ = 0;
  uint64_t done_ = 0;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

// A bar when stderr is a terminal, silence otherwise.
std::unique_ptr<Progress> make_progress_for_stderr();

}  // namespace relief
