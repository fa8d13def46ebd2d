#include "writeback.h"

#include <fcntl.h>
#include <unistd.h>

namespace relief::ingest {

Writeback::Writeback() : thread_([this](std::stop_token stop) { run(stop); }) {}

Writeback::~Writeback() {
  thread_.request_stop();
  thread_.join();
}

void Writeback::start(std::filesystem::path file) {
  {
    std::lock_guard lock(mutex_);
    files_.push_back(std::move(file));
  }
  queued_.notify_one();
}

void Writeback::run(std::stop_token stop) {
  std::unique_lock lock(mutex_);
  while (queued_.wait(lock, stop, [&] { return !files_.empty(); })) {
    const std::filesystem::path file = std::move(files_.front());
    files_.pop_front();
    lock.unlock();
    const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
      ::sync_file_range(fd, 0, 0, SYNC_FILE_RANGE_WRITE);
      ::close(fd);
    }
    lock.lock();
  }
}

}  // namespace relief::ingest
