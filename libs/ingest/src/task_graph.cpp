#include "task_graph.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>

namespace relief::ingest {

size_t TaskGraph::add(int task_class) {
  assert(task_class >= 0 && task_class < kClasses);
  tasks_.push_back({task_class, 0, {}});
  return tasks_.size() - 1;
}

void TaskGraph::depend(size_t task, size_t prerequisite) {
  assert(prerequisite < task && task < tasks_.size());
  tasks_[prerequisite].dependents.push_back(task);
  ++tasks_[task].waiting_for;
}

void TaskGraph::run(Executor& executor, const std::function<void(size_t)>& body) {
  std::mutex mutex;
  std::condition_variable changed;
  std::array<std::deque<size_t>, kClasses> ready;
  std::vector<size_t> waiting(tasks_.size());
  for (size_t id = 0; id < tasks_.size(); ++id) {
    waiting[id] = tasks_[id].waiting_for;
    if (waiting[id] == 0) ready[static_cast<size_t>(tasks_[id].task_class)].push_back(id);
  }
  size_t finished = 0;
  size_t first_class_running = 0;
  // The next task for a worker, or nothing when none is ready (under mutex).
  auto next = [&]() -> std::optional<size_t> {
    const bool others_ready =
        std::any_of(ready.begin() + 1, ready.end(), [](const auto& q) { return !q.empty(); });
    size_t from = 0;
    if (ready[0].empty() || (first_class_running > 0 && others_ready)) {
      from = 1;
      while (from < ready.size() && ready[from].empty()) ++from;
      if (from == ready.size()) return std::nullopt;
    }
    const size_t id = ready[from].front();
    ready[from].pop_front();
    return id;
  };
  auto worker = [&](size_t) {
    std::unique_lock lock(mutex);
    while (finished < tasks_.size()) {
      const std::optional<size_t> id = next();
      if (!id) {
        changed.wait(lock);
        continue;
      }
      const bool first_class = tasks_[*id].task_class == 0;
      first_class_running += first_class;
      lock.unlock();
      body(*id);
      lock.lock();
      first_class_running -= first_class;
      ++finished;
      for (size_t d : tasks_[*id].dependents) {
        if (--waiting[d] == 0) ready[static_cast<size_t>(tasks_[d].task_class)].push_back(d);
      }
      changed.notify_all();
    }
  };
  executor.parallel_for(std::min<size_t>(executor.concurrency(), tasks_.size()), worker);
}

}  // namespace relief::ingest
