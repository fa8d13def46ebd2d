#include "cpu_layer_processing.h"

#include <algorithm>
#include <chrono>
#include <limits>

#include "relief/base/parallel.h"

namespace relief::render {
namespace {

// A result marked while its job runs.
bool running(const Result<lod::TilePtr>& r) {
  return r && !*r;
}

}  // namespace

CpuLayerProcessing::CpuLayerProcessing(unsigned threads, std::function<void()> on_done)
    : on_done_(std::move(on_done)) {
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  for (unsigned i = 0; i < threads; ++i) threads_.emplace_back([this] { work(); });
}

CpuLayerProcessing::~CpuLayerProcessing() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    queued_.clear();
  }
  wake_.notify_all();
  threads_.clear();  // joins
}

Result<lod::TilePtr> CpuLayerProcessing::get_or_submit(const Key& key, Job job) {
  std::lock_guard lock(mutex_);
  if (auto it = done_.find(key); it != done_.end()) return it->second.result;  // null: running
  if (auto it = queued_.find(key); it != queued_.end()) {
    it->second.priority = std::max(it->second.priority, job.priority);
    it->second.frame = frame_;
    return lod::TilePtr();
  }
  job.frame = frame_;
  queued_.emplace(key, std::move(job));
  wake_.notify_one();
  return lod::TilePtr();
}

void CpuLayerProcessing::forget(const Key& key) {
  std::lock_guard lock(mutex_);
  if (auto it = done_.find(key); it != done_.end() && !running(it->second.result)) {
    done_.erase(it);
  }
}

bool CpuLayerProcessing::wait_idle(double seconds) {
  std::unique_lock lock(mutex_);
  const auto idle = [&] {
    return queued_.empty() &&
           std::ranges::none_of(done_, [](const auto& e) { return running(e.second.result); });
  };
  if (!(seconds < std::numeric_limits<double>::infinity())) {
    finished_cv_.wait(lock, idle);
    return true;
  }
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                         std::chrono::duration<double>(std::max(0.0, seconds)));
  return finished_cv_.wait_until(lock, until, idle);
}

double CpuLayerProcessing::estimated_seconds() {
  std::lock_guard lock(mutex_);
  const auto jobs =
      queued_.size() + static_cast<size_t>(std::ranges::count_if(
                           done_, [](const auto& e) { return running(e.second.result); }));
  const size_t rounds = (jobs + threads_.size() - 1) / threads_.size();
  return static_cast<double>(rounds) * job_seconds_;
}

void CpuLayerProcessing::begin_frame() {
  std::lock_guard lock(mutex_);
  std::erase_if(queued_, [&](const auto& e) { return e.second.frame < frame_; });
  ++frame_;
}

void CpuLayerProcessing::drop_before(uint32_t version) {
  std::lock_guard lock(mutex_);
  std::erase_if(queued_, [&](const auto& e) { return e.first.version < version; });
  // Running jobs of older versions stay marked; their results are dropped
  // when they finish.
  std::erase_if(
      done_, [&](const auto& e) { return e.first.version < version && !running(e.second.result); });
  latest_version_ = std::max(latest_version_, version);
}

void CpuLayerProcessing::work() {
  InlineExecutor inline_executor;  // one tile per worker: the workers are the parallelism
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stopping_ || !queued_.empty(); });
    if (stopping_) return;
    auto next = std::ranges::max_element(queued_, [](const auto& a, const auto& b) {
      return a.second.priority < b.second.priority;
    });
    const Key key = next->first;
    Job job = std::move(next->second);
    queued_.erase(next);
    done_[key] = {lod::TilePtr(), 0};  // running
    lock.unlock();
    const auto start = std::chrono::steady_clock::now();
    Result<tiles::Raster> out =
        gpuprocess::run_chain_cpu(job.chain, *job.tile, job.border, &job.stats, inline_executor);
    if (out && job.colours) {
      const Job::Colours& c = *job.colours;
      *out = gpuprocess::map_colours_cpu(*out, c.range_min, c.range_max, c.map, c.opacity);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    lock.lock();
    job_seconds_ = finished_ == 0 ? seconds : 0.8 * job_seconds_ + 0.2 * seconds;
    finished_cv_.notify_all();  // wait_idle: checked once the result is in (below)
    if (key.version < latest_version_) {
      done_.erase(key);
      continue;
    }
    Done& d = done_[key];
    d.order = ++finished_;
    if (out) {
      d.result = std::make_shared<const tiles::Raster>(std::move(*out));
    } else {
      d.result = fail(out.error().message);
    }
    if (done_.size() > kMaxResults) {
      auto oldest = done_.end();
      for (auto it = done_.begin(); it != done_.end(); ++it) {
        if (running(it->second.result)) continue;
        if (oldest == done_.end() || it->second.order < oldest->second.order) oldest = it;
      }
      if (oldest != done_.end()) done_.erase(oldest);
    }
    if (on_done_) {
      lock.unlock();
      on_done_();
      lock.lock();
    }
  }
}

}  // namespace relief::render
