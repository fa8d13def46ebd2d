#pragma once
// A fixed set of tasks with dependencies, run to completion by an Executor's
// workers: a task starts once every task it depends on has finished, so
// phases that used to wait for each other overlap (a pyramid parent starts as
// soon as its four children exist, a tile as soon as its 3 x 3 neighbourhood
// does) and no worker waits at a phase boundary while another finishes.
//
// Ready tasks are taken by class (lower first) and, within a class, in the
// order they became ready (the order of `add` for those ready from the
// start), so a build with one worker runs in a fixed order. Tasks of class 0
// run one at a time while a task of another class is ready: the build's
// warps, whose reads of a shared mosaic are serialised, would otherwise make
// the second worker wait for the first's read instead of doing other work.
#include <cstddef>
#include <functional>
#include <vector>

#include "relief/base/parallel.h"

namespace relief::ingest {

class TaskGraph {
 public:
  // A new task of `task_class` (0 .. kClasses - 1); returns its id.
  size_t add(int task_class);
  // `task` starts only after `prerequisite` (added earlier) has finished.
  void depend(size_t task, size_t prerequisite);
  size_t size() const { return tasks_.size(); }

  // Calls body(id) once for every task, on up to executor.concurrency()
  // workers, and returns when all have returned. body must not throw.
  void run(Executor& executor, const std::function<void(size_t)>& body);

  static constexpr int kClasses = 4;

 private:
  struct Task {
    int task_class;
    size_t waiting_for = 0;          // unfinished prerequisites
    std::vector<size_t> dependents;  // tasks waiting for this one
  };
  std::vector<Task> tasks_;
};

}  // namespace relief::ingest
