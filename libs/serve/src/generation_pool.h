#pragma once
// The threads that make generated answers (ServeOptions::generate) off the
// event loops: a web tile takes 10-60 ms to make, and a loop that made it
// itself would keep every other connection it serves waiting that long.
// Jobs run in the order given; stop() drops those not started and waits
// for those running.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace relief::serve {

class GenerationPool {
 public:
  explicit GenerationPool(int threads);
  ~GenerationPool() { stop(); }
  GenerationPool(const GenerationPool&) = delete;
  GenerationPool& operator=(const GenerationPool&) = delete;

  void submit(std::function<void()> job);
  void stop();

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace relief::serve
