#include "relief/video/video_writer.h"

#include <cassert>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>

#include "encoder.h"
#include "relief/base/file_io.h"

namespace relief::video {

namespace fs = std::filesystem;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

// The caller's thread fills `queue`; the encoder's thread empties it. An
// encoder error is kept and returned by the next write() or by finish().
struct VideoWriter::Impl {
  fs::path path, temporary;
  size_t frame_bytes = 0;
  size_t capacity = 0;
  std::unique_ptr<Encoder> encoder;
  bool finished = false;

  std::mutex mutex;
  std::condition_variable space, work;
  std::deque<std::vector<uint8_t>> queue;  // guarded by mutex
  bool closing = false;                    // guarded by mutex
  std::optional<Error> error;              // guarded by mutex
  VideoStats stats;                        // frames and encode_seconds: encoder thread
  std::thread thread;

  void run() {
    for (;;) {
      std::vector<uint8_t> frame;
      {
        std::unique_lock lock(mutex);
        work.wait(lock, [&] { return !queue.empty() || closing; });
        if (queue.empty()) return;  // closing, all encoded
        frame = std::move(queue.front());
        queue.pop_front();
      }
      space.notify_one();
      const auto start = std::chrono::steady_clock::now();
      Status st = encoder->encode(frame);
      stats.encode_seconds += seconds_since(start);
      ++stats.frames;
      if (!st) {
        std::lock_guard lock(mutex);
        error = st.error();
        queue.clear();  // write() returns the error from now on
        space.notify_all();
        return;
      }
    }
  }

  void stop() {
    {
      std::lock_guard lock(mutex);
      closing = true;
    }
    work.notify_one();
    if (thread.joinable()) thread.join();
  }

  // Abandons the movie: the temporary file goes, the target is untouched.
  void discard() {
    stop();
    encoder.reset();
    std::error_code ec;
    fs::remove(temporary, ec);
  }
};

VideoWriter::VideoWriter(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

VideoWriter::~VideoWriter() {
  if (impl_ && !impl_->finished) impl_->discard();
}

Result<std::unique_ptr<VideoWriter>> VideoWriter::open(const fs::path& path, int width, int height,
                                                       double fps, const VideoOptions& options) {
  RELIEF_CHECK(check_options(options));
  RELIEF_CHECK(check_replaceable(path));
  if (path.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    if (ec) {
      return fail(fmt::format("{}: cannot create its directory: {}", path.string(), ec.message()));
    }
  }
  (void)remove_stale_temporaries_of(path);  // of killed exports; best effort
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->temporary = temporary_name(path);
  impl->frame_bytes = static_cast<size_t>(width) * static_cast<size_t>(height) * 4;
  impl->capacity = static_cast<size_t>(options.queue_frames);
  auto encoder =
      Encoder::open(impl->temporary.string(), path.string(), width, height, fps, options);
  if (!encoder) {
    std::error_code ec;
    fs::remove(impl->temporary, ec);
    return std::unexpected(encoder.error());
  }
  impl->encoder = std::move(*encoder);
  impl->thread = std::thread([m = impl.get()] { m->run(); });
  return std::unique_ptr<VideoWriter>(new VideoWriter(std::move(impl)));
}

Status VideoWriter::write(std::vector<uint8_t> rgba) {
  Impl& m = *impl_;
  assert(!m.finished);
  assert(rgba.size() == m.frame_bytes);
  const auto start = std::chrono::steady_clock::now();
  {
    std::unique_lock lock(m.mutex);
    m.space.wait(lock, [&] { return m.queue.size() < m.capacity || m.error; });
    if (m.error) return std::unexpected(*m.error);
    m.queue.push_back(std::move(rgba));
  }
  m.stats.write_wait_seconds += seconds_since(start);
  m.work.notify_one();
  return {};
}

Result<VideoStats> VideoWriter::finish() {
  Impl& m = *impl_;
  assert(!m.finished);
  m.stop();
  Status st = m.error ? Status(std::unexpected(*m.error)) : m.encoder->finish();
  if (st) {
    std::error_code ec;
    fs::rename(m.temporary, m.path, ec);
    if (ec)
      st = fail(fmt::format("{}: cannot rename the finished movie onto it: {}", m.path.string(),
                            ec.message()));
  }
  if (!st) {
    m.discard();
    m.finished = true;
    return std::unexpected(st.error());
  }
  m.finished = true;
  m.encoder.reset();
  std::error_code ec;
  m.stats.bytes = fs::file_size(m.path, ec);
  return m.stats;
}

}  // namespace relief::video
