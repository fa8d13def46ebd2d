#pragma once
// Starts the kernel's writeback of finished tile files while the build goes
// on, so the syncfs that makes the store durable before its manifest finds
// little left to write: on the 24-tile Himalaya block that sync was 0.2 s of
// waiting with both cores idle, at the very end of the build. Each file is
// handed to a thread of its own that calls sync_file_range(WRITE) on it
// (asynchronous: it queues the writes, waits for none), so a worker never
// blocks on the disk. Only an optimisation: durability still comes from the
// syncfs, and a file that cannot be opened here is simply left to it.
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
#include <thread>

namespace relief::ingest {

class Writeback {
 public:
  Writeback();
  // Drops what was not started yet (the syncfs writes it) and joins the thread.
  ~Writeback();
  Writeback(const Writeback&) = delete;
  Writeback& operator=(const Writeback&) = delete;

  // Queues the writeback of `file`, whose contents are final. Thread-safe.
  void start(std::filesystem::path file);

 private:
  void run(std::stop_token stop);

  std::mutex mutex_;
  std::condition_variable_any queued_;
  std::deque<std::filesystem::path> files_;
  std::jthread thread_;  // last: started after the members it uses
};

}  // namespace relief::ingest
