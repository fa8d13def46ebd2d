#include "relief/stream/tile_loader.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <list>
#include <mutex>
#include <semaphore>
#include <thread>
#include <unordered_map>

#include <pthread.h>
#include <sys/resource.h>
#include <unistd.h>

#include "relief/tiles/store.h"

namespace relief::stream {

namespace {

using geo::TileKey;

// Prefetch priorities are scaled into a band below every current request.
constexpr double kPrefetchScale = 1e-12;

struct Entry {
  TileState state = TileState::Absent;
  lod::TilePtr tile;
  uint64_t bytes = 0;
  std::list<TileKey>::iterator lru;  // Resident only
  bool permanent = false;            // level 0
  bool prefetch = false;             // loaded for a predicted view, not drawn yet
  bool forgotten = false;            // TileProvider::forget while pinned
  Clock::TimePoint failed_at;
  uint32_t failures = 0;  // in a row, reset by a load
};

struct Request {
  TileKey key;
  double priority;
  bool prefetch;
};

// Names the calling thread and lowers its CPU priority by `nice` steps. Best
// effort: raising one's own nice value needs no privilege, and a loader whose
// workers kept the normal priority still works.
void become_loader_worker(int nice) {
  pthread_setname_np(pthread_self(), "relief-loader");
  if (nice <= 0) return;
  const auto tid = static_cast<id_t>(gettid());
  errno = 0;
  const int current = getpriority(PRIO_PROCESS, tid);  // -1 is a valid nice value
  if (errno != 0) return;
  setpriority(PRIO_PROCESS, tid, std::min(19, current + nice));
}

}  // namespace

const char* to_string(TileState s) {
  switch (s) {
    case TileState::Absent:
      return "absent";
    case TileState::Queued:
      return "queued";
    case TileState::Loading:
      return "loading";
    case TileState::Resident:
      return "resident";
    case TileState::Failed:
      return "failed";
  }
  return "?";
}

const char* to_string(TileEventKind k) {
  switch (k) {
    case TileEventKind::Requested:
      return "requested";
    case TileEventKind::Cancelled:
      return "cancelled";
    case TileEventKind::Started:
      return "started";
    case TileEventKind::Loaded:
      return "loaded";
    case TileEventKind::Failed:
      return "failed";
    case TileEventKind::Evicted:
      return "evicted";
  }
  return "?";
}

struct TileLoader::Impl {
  const tiles::Store& store;
  LoaderOptions options;
  mutable std::mutex mutex;
  std::condition_variable wake, ready;
  bool stopping = false;
  int workers_ready = 0;  // set their priority: create() returns after all have
  std::unordered_map<TileKey, Entry, geo::TileKeyHash> entries;
  std::list<TileKey> lru;      // resident, most recent first
  std::vector<Request> queue;  // ascending priority: workers take the back
  std::vector<TileEvent> events;
  // Forgotten while pinned: evicted in a later begin_frame(), once unpinned.
  std::vector<TileKey> forgotten;
  LoaderStats counters;
  uint64_t resident_bytes = 0;
  uint32_t in_flight = 0, prefetch_in_flight = 0;
  uint32_t announcing = 0;  // on_settled calls running (the loader is not idle until they return)
  // Render thread only.
  std::unordered_map<TileKey, Request, geo::TileKeyHash> frame_requests;
  std::vector<std::function<void(const TileEvent&)>> listeners;
  std::shared_ptr<const lod::TileProvider::Prepare> prepare;  // run by workers after decoding
  std::vector<std::thread> workers;
  std::counting_semaphore<> preparing;                   // LoaderOptions::max_preparing
  std::atomic<int> preparing_now{0}, preparing_most{0};  // LoaderStats::most_preparing

  Impl(const tiles::Store& s, const LoaderOptions& o)
      : store(s), options(o), preparing(preparing_slots(o)) {}

  static std::ptrdiff_t preparing_slots(const LoaderOptions& o) {
    return o.max_preparing > 0 ? o.max_preparing : std::max(o.max_in_flight, 1);
  }

  // Runs the Prepare step within LoaderOptions::max_preparing.
  void prepare_tile(const lod::TileProvider::Prepare& prepare_step, const TileKey& key,
                    const tiles::Raster& tile) {
    preparing.acquire();
    const int now = preparing_now.fetch_add(1) + 1;
    for (int most = preparing_most.load(); now > most;) {
      if (preparing_most.compare_exchange_weak(most, now)) break;
    }
    prepare_step(key, tile);
    preparing_now.fetch_sub(1);
    preparing.release();
  }

  // Every state change goes through here (mutex held).
  void move(const TileKey& key, Entry& e, TileState to, TileEvent event) {
    assert(allowed(e.state, to));
    e.state = to;
    event.key = key;
    events.push_back(std::move(event));
  }

  void erase(const TileKey& key) { entries.erase(key); }

  bool pinned(const Entry& e) const { return e.permanent || e.tile.use_count() > 1; }

  // Evicts unpinned tiles other than `keep`, least recently used first,
  // until within budget.
  void evict_to_budget(const TileKey& keep) {
    for (auto it = lru.end(); resident_bytes > options.memory_budget && it != lru.begin();) {
      --it;
      Entry& e = entries.at(*it);
      if (pinned(e) || *it == keep) continue;
      const TileKey key = *it;
      it = evict(key, e);
    }
  }

  // TileProvider::forget: evicts a resident tile now, or once no caller
  // holds it (a frame pins the tiles it looked at until the next begin);
  // false when it is still pinned.
  bool forget(const TileKey& key) {
    auto it = entries.find(key);
    if (it == entries.end() || it->second.state != TileState::Resident || it->second.permanent) {
      return true;
    }
    if (pinned(it->second)) {
      it->second.forgotten = true;
      return false;
    }
    evict(key, it->second);
    return true;
  }
  // The tiles forgotten while pinned (not those loaded again since).
  void forget_unpinned() {
    std::erase_if(forgotten, [&](const TileKey& key) {
      auto it = entries.find(key);
      return it == entries.end() || !it->second.forgotten || forget(key);
    });
  }

  // Drops resident, unpinned entry `e`: the next position in the LRU list.
  std::list<TileKey>::iterator evict(const TileKey& key, Entry& e) {
    auto next = lru.erase(e.lru);
    resident_bytes -= e.bytes;
    ++counters.evicted;
    move(key, e, TileState::Absent, {TileEventKind::Evicted, key, e.bytes, e.prefetch, {}});
    erase(key);
    return next;
  }

  void make_resident(const TileKey& key, Entry& e, lod::TilePtr tile) {
    e.bytes = tile->byte_size();
    e.tile = std::move(tile);
    lru.push_front(key);
    e.lru = lru.begin();
    resident_bytes += e.bytes;
  }

  // The best request, except that a quarter of the loads in flight may go
  // to the best prefetch request: otherwise, on a busy link, the current
  // view always has something queued and prefetch would never run.
  Request take_next() {
    auto pick = std::prev(queue.end());
    if (!pick->prefetch && 4 * prefetch_in_flight < static_cast<uint32_t>(options.max_in_flight) &&
        in_flight > 0) {
      for (auto it = queue.rbegin(); it != queue.rend(); ++it) {
        if (it->prefetch) {
          pick = std::prev(it.base());
          break;
        }
      }
    }
    const Request r = *pick;
    queue.erase(pick);
    return r;
  }

  // Backoff: the pause before a failed tile loads again.
  double retry_pause(const Entry& e) const {
    const int doublings = static_cast<int>(std::min<uint32_t>(e.failures, 32)) - 1;
    return std::min(options.retry_failed_max,
                    std::ldexp(options.retry_failed_after, std::max(0, doublings)));
  }

  void work() {
    become_loader_worker(options.worker_nice);
    std::unique_lock lock(mutex);
    ++workers_ready;
    ready.notify_all();
    for (;;) {
      wake.wait(lock, [&] { return stopping || !queue.empty(); });
      if (stopping) return;
      const Request r = take_next();
      Entry& e = entries.at(r.key);
      move(r.key, e, TileState::Loading, {TileEventKind::Started, r.key, 0, r.prefetch, {}});
      ++in_flight;
      prefetch_in_flight += r.prefetch;
      const auto prepare_step = prepare;
      lock.unlock();
      Result<lod::TilePtr> tile = lod::decode_tile(store, r.key);
      if (tile && prepare_step && *prepare_step) this->prepare_tile(*prepare_step, r.key, **tile);
      const tiles::IndexEntry* ie = store.index(r.key.level).find(r.key);
      lock.lock();
      --in_flight;
      prefetch_in_flight -= r.prefetch;
      Entry& done = entries.at(r.key);  // Loading entries are never erased by others
      if (!tile) {
        ++counters.failed;
        done.failed_at = options.clock->now();
        ++done.failures;
        move(r.key, done, TileState::Failed,
             {TileEventKind::Failed, r.key, 0, r.prefetch, tile.error().message});
        settled(lock);
        continue;
      }
      done.failures = 0;
      counters.bytes_fetched += ie ? ie->file_bytes : 0;
      ++counters.loaded;
      if (r.prefetch) ++counters.prefetched;
      done.prefetch = r.prefetch;
      move(r.key, done, TileState::Resident,
           {TileEventKind::Loaded, r.key, (*tile)->byte_size(), r.prefetch, {}});
      make_resident(r.key, done, std::move(*tile));
      evict_to_budget(r.key);
      if (resident_bytes > options.memory_budget) {
        evict(r.key, done);  // everything else is pinned: this one does not fit
      }
      settled(lock);
    }
  }

  // LoaderOptions::on_settled, without the lock (the listener may ask for stats()).
  void settled(std::unique_lock<std::mutex>& lock) {
    if (!options.on_settled) return;
    ++announcing;
    lock.unlock();
    options.on_settled();
    lock.lock();
    --announcing;
  }
};

TileLoader::TileLoader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

TileLoader::~TileLoader() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->wake.notify_all();
  for (auto& t : impl_->workers) t.join();
}

Result<std::unique_ptr<TileLoader>> TileLoader::create(const tiles::Store& store,
                                                       const LoaderOptions& options) {
  if (options.max_in_flight < 1) return fail("loader: at least one load must be allowed in flight");
  assert(options.clock);
  auto impl = std::make_unique<Impl>(store, options);
  for (const tiles::IndexEntry& ie : store.index(0).entries()) {
    lod::TilePtr tile = RELIEF_TRY(lod::decode_tile(store, ie.key));
    Entry& e = impl->entries[ie.key];
    e.state = TileState::Resident;
    e.permanent = true;
    impl->make_resident(ie.key, e, std::move(tile));
    impl->counters.bytes_fetched += ie.file_bytes;
    ++impl->counters.loaded;
  }
  for (int i = 0; i < options.max_in_flight; ++i) {
    impl->workers.emplace_back([p = impl.get()] { p->work(); });
  }
  {
    // No load starts before every worker runs at its priority.
    std::unique_lock lock(impl->mutex);
    impl->ready.wait(lock, [&] { return impl->workers_ready == options.max_in_flight; });
  }
  return std::unique_ptr<TileLoader>(new TileLoader(std::move(impl)));
}

Result<lod::TilePtr> TileLoader::get(const TileKey& key) {
  std::lock_guard lock(impl_->mutex);
  auto it = impl_->entries.find(key);
  if (it == impl_->entries.end() || it->second.state != TileState::Resident) {
    ++impl_->counters.misses;
    return lod::TilePtr{};
  }
  ++impl_->counters.hits;
  Entry& e = it->second;
  impl_->lru.splice(impl_->lru.begin(), impl_->lru, e.lru);
  if (e.prefetch && !prefetching_) {
    e.prefetch = false;
    ++impl_->counters.prefetch_used;
  }
  return e.tile;
}

void TileLoader::request(const TileKey& key, double priority) {
  const double p = prefetching_ ? priority * kPrefetchScale : priority;
  auto [it, added] = impl_->frame_requests.try_emplace(key, Request{key, p, prefetching_});
  if (!added) {
    it->second.priority = std::max(it->second.priority, p);
    it->second.prefetch = it->second.prefetch && prefetching_;
  }
}

void TileLoader::begin_frame() {
  impl_->frame_requests.clear();
  std::vector<TileEvent> events;
  {
    std::lock_guard lock(impl_->mutex);
    impl_->forget_unpinned();
    events.swap(impl_->events);
  }
  for (const TileEvent& e : events) {
    for (const auto& listener : impl_->listeners) listener(e);
  }
}

void TileLoader::end_frame() {
  Impl& m = *impl_;
  size_t to_wake = 0;
  {
    std::lock_guard lock(m.mutex);
    // Stale requests: queued, but no longer wanted.
    for (const Request& r : m.queue) {
      if (m.frame_requests.contains(r.key)) continue;
      ++m.counters.cancelled;
      m.move(r.key, m.entries.at(r.key), TileState::Absent,
             {TileEventKind::Cancelled, r.key, 0, r.prefetch, {}});
      m.erase(r.key);
    }
    m.queue.clear();
    const auto now = m.options.clock->now();
    for (const auto& [key, r] : m.frame_requests) {
      Entry& e = m.entries[key];
      if (e.state == TileState::Failed && seconds_between(e.failed_at, now) >= m.retry_pause(e)) {
        m.move(key, e, TileState::Absent, {TileEventKind::Evicted, key, 0, r.prefetch, {}});
      }
      if (e.state == TileState::Absent) {
        ++m.counters.requested;
        m.move(key, e, TileState::Queued, {TileEventKind::Requested, key, 0, r.prefetch, {}});
      }
      if (e.state == TileState::Queued) m.queue.push_back(r);
    }
    std::sort(m.queue.begin(), m.queue.end(), [](const Request& a, const Request& b) {
      return a.priority != b.priority ? a.priority < b.priority : b.key < a.key;
    });
    to_wake = std::min(m.queue.size(), m.workers.size());
    m.counters.woken += to_wake;
  }
  // Wake no more workers than there are tiles to load. A worker woken for
  // nothing still takes a core to find the queue empty: on two cores the
  // render thread lost 1.6-9 ms (3.8 on average) in the broadcast of a
  // quarter of bench/view's Himalaya frames, which queued nothing new.
  // (Workers look at the queue under the lock before they wait: none misses
  // a tile queued while it was busy.)
  for (size_t i = 0; i < to_wake; ++i) m.wake.notify_one();
}

void TileLoader::forget(const geo::TileKey& key) {
  std::lock_guard lock(impl_->mutex);
  if (!impl_->forget(key)) impl_->forgotten.push_back(key);
}

void TileLoader::set_prepare(Prepare prepare) {
  std::lock_guard lock(impl_->mutex);
  impl_->prepare = std::make_shared<const Prepare>(std::move(prepare));
}

void TileLoader::subscribe(std::function<void(const TileEvent&)> listener) {
  impl_->listeners.push_back(std::move(listener));
}

LoaderStats TileLoader::stats() const {
  std::lock_guard lock(impl_->mutex);
  LoaderStats s = impl_->counters;
  s.most_preparing = static_cast<uint32_t>(impl_->preparing_most.load());
  s.memory_budget = impl_->options.memory_budget;
  s.resident_bytes = impl_->resident_bytes;
  s.queued = static_cast<uint32_t>(impl_->queue.size());
  s.in_flight = impl_->in_flight;
  for (const auto& [key, e] : impl_->entries) {
    if (e.state != TileState::Resident) continue;
    if (s.resident_per_level.size() <= static_cast<size_t>(key.level)) {
      s.resident_per_level.resize(static_cast<size_t>(key.level) + 1);
    }
    ++s.resident_per_level[static_cast<size_t>(key.level)].tiles;
    s.resident_per_level[static_cast<size_t>(key.level)].bytes += e.bytes;
    ++s.resident_tiles;
    if (impl_->pinned(e)) s.pinned_bytes += e.bytes;
  }
  return s;
}

uint64_t TileLoader::resident_bytes() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->resident_bytes;
}

TileState TileLoader::state(const TileKey& key) const {
  std::lock_guard lock(impl_->mutex);
  auto it = impl_->entries.find(key);
  return it == impl_->entries.end() ? TileState::Absent : it->second.state;
}

bool TileLoader::idle() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->queue.empty() && impl_->in_flight == 0 && impl_->announcing == 0;
}

}  // namespace relief::stream
