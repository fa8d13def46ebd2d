#include "relief/video/video_writer.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <future>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>

#include "codecs.h"
#include "encoder.h"
#include "relief/base/file_io.h"
#include "relief/base/module.h"

namespace relief::video {

namespace fs = std::filesystem;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The encoder module, loaded once, on the first movie (encoder.h says why).
Result<OpenEncoder> load_encoder() {
  static std::mutex mutex;
  static OpenEncoder open = nullptr;
  std::lock_guard lock(mutex);
  if (open) return open;
  const ModuleLocation location{.what = "video",
                                .description = "FFmpeg encoder module",
                                .env_variable = "RELIEF_VIDEO_MODULE",
                                .build_path = RELIEF_VIDEO_MODULE_BUILD_PATH};
  void* symbol = RELIEF_TRY(load_module_symbol(location, kOpenEncoderSymbol, SymbolScope::local));
  open = reinterpret_cast<OpenEncoder>(symbol);
  return open;
}

// The encoder's thread (and the codec's own threads, which inherit it) runs
// this much nicer than the render thread: on a machine with few cores,
// encoding takes the CPU time rendering leaves idle (the single-threaded
// parts of a frame) instead of competing with the rasteriser's threads.
// Linux's nice value is per thread. Best effort: a failure changes nothing.
constexpr int kEncoderNicer = 10;

void lower_this_threads_priority() {
  const auto tid = static_cast<id_t>(gettid());
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, tid);
  if (errno == 0) (void)setpriority(PRIO_PROCESS, tid, std::min(nice + kEncoderNicer, 19));
}

// "a, b, c": the names an option accepts, for its help and its errors.
template <class Names, class Name>
std::string comma_separated(const Names& names, Name name_of) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + std::string(name_of(n));
  return out;
}

}  // namespace

std::string codec_names() {
  return comma_separated(kCodecs, [](const CodecName& c) { return c.name; });
}

std::string preset_names() {
  return comma_separated(kPresets, [](const char* p) { return p; });
}

Status check_options(const VideoOptions& options) {
  bool known = false;
  for (const CodecName& c : kCodecs) known = known || options.codec == c.name;
  if (!known) {
    return fail(
        fmt::format("--codec: '{}' is not a supported codec ({})", options.codec, codec_names()));
  }
  if (options.crf < 0 || options.crf > 51) return fail("--crf: must be in [0, 51]");
  bool preset = false;
  for (const char* p : kPresets) preset = preset || options.preset == p;
  if (!preset) {
    return fail(
        fmt::format("--preset: '{}' is not an x264 preset ({})", options.preset, preset_names()));
  }
  if (options.queue_frames < 1) return fail("video: the queue needs at least one frame");
  return {};
}

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
  struct Frame {
    std::vector<uint8_t> rgba;
    RowOrder rows;
  };
  std::deque<Frame> queue;                  // guarded by mutex
  std::vector<std::vector<uint8_t>> spare;  // encoded frames' buffers; guarded by mutex
  bool closing = false;                     // guarded by mutex
  std::optional<Error> error;               // guarded by mutex
  VideoStats stats;                         // frames and encode_seconds: encoder thread
  std::thread thread;

  void run() {
    for (;;) {
      Frame frame;
      {
        std::unique_lock lock(mutex);
        work.wait(lock, [&] { return !queue.empty() || closing; });
        if (queue.empty()) return;  // closing, all encoded
        frame = std::move(queue.front());
        queue.pop_front();
      }
      space.notify_one();
      const auto start = std::chrono::steady_clock::now();
      Status st = encoder->encode(frame.rgba, frame.rows);
      stats.encode_seconds += seconds_since(start);
      ++stats.frames;
      {
        std::lock_guard lock(mutex);
        if (spare.size() < capacity) spare.push_back(std::move(frame.rgba));
      }
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
  if (width <= 0 || height <= 0 || width % 2 || height % 2) {
    return fail(fmt::format("{}: {}x{}: a movie (H.264, yuv420p) needs an even width and height",
                            path.string(), width, height));
  }
  if (!(fps > 0 && fps <= 1000)) {
    return fail(fmt::format("{}: {} fps: must be in (0, 1000]", path.string(), fps));
  }
  const OpenEncoder open_encoder = RELIEF_TRY(load_encoder());
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
  // Opened on the encoder's thread, after it lowered its priority: the
  // codec's threads are created here and inherit it.
  std::promise<Status> opened;
  std::future<Status> result = opened.get_future();
  impl->thread = std::thread([&, m = impl.get()] {
    lower_this_threads_priority();
    auto encoder = open_encoder(m->temporary.string(), path.string(), width, height, fps, options);
    if (!encoder) {
      opened.set_value(std::unexpected(encoder.error()));
      return;
    }
    m->encoder = std::move(*encoder);
    opened.set_value({});  // from here on, nothing of open()'s frame is used
    m->run();
  });
  if (Status st = result.get(); !st) {
    impl->thread.join();
    std::error_code ec;
    fs::remove(impl->temporary, ec);
    return std::unexpected(st.error());
  }
  return std::unique_ptr<VideoWriter>(new VideoWriter(std::move(impl)));
}

std::vector<uint8_t> VideoWriter::take_buffer() {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.mutex);
    if (!m.spare.empty()) {
      std::vector<uint8_t> buffer = std::move(m.spare.back());
      m.spare.pop_back();
      return buffer;
    }
  }
  return std::vector<uint8_t>(m.frame_bytes);
}

Status VideoWriter::write(std::vector<uint8_t> rgba, RowOrder rows) {
  Impl& m = *impl_;
  assert(!m.finished);
  assert(rgba.size() == m.frame_bytes);
  const auto start = std::chrono::steady_clock::now();
  {
    std::unique_lock lock(m.mutex);
    m.space.wait(lock, [&] { return m.queue.size() < m.capacity || m.error; });
    if (m.error) return std::unexpected(*m.error);
    m.queue.push_back({std::move(rgba), rows});
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
