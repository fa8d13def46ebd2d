// Top-down refinement in lanes on an executor's threads: the quads dealt
// out, a refiner per lane walking its own in rounds until no inbox holds a
// split, then the lanes' statistics and triangles gathered.
#include <algorithm>
#include <ctime>
#include <functional>
#include <thread>
#include <unordered_map>

#include "refiner.h"

namespace relief::lod::refinement {

// Lanes: a copy of this refiner (after prepare() and seed_top_down()) that
// refines the quads `lanes` gives lane `lane`, with its own mark blocks,
// starting from their seeds.
Refiner Refiner::lane(Lanes& lanes, uint32_t lane, MarkBlocks& blocks) const {
  Refiner r = *this;
  r.lanes_ = &lanes;
  r.lane_ = lane;
  r.blocks_ = &blocks;
  r.stats_ = {};
  r.work_.clear();
  for (const Located& l : work_) {
    if (r.mine(l.quad)) r.work_.push_back(l);
  }
  r.outbox_.assign(lanes.inboxes.size(), {});
  return r;
}

// This lane's statistics added to those of the refiner it was copied from.
void Refiner::merge(const Refiner& lane) {
  stats_.marks_evaluated += lane.stats_.marks_evaluated;
  stats_.marks_near += lane.stats_.marks_near;
  stats_.max_unresolved_pixels =
      std::max(stats_.max_unresolved_pixels, lane.stats_.max_unresolved_pixels);
  unresolved_keys_.insert(unresolved_keys_.end(), lane.unresolved_keys_.begin(),
                          lane.unresolved_keys_.end());
  for (const geo::TileKey& k : lane.stats_.split_wanted) {
    auto& wanted = stats_.split_wanted;
    if (std::find(wanted.begin(), wanted.end(), k) == wanted.end()) wanted.push_back(k);
  }
}

// After the lanes merged: a diamond both lanes of a shared side found
// stuck is counted once, as by one refiner.
void Refiner::count_unresolved() {
  std::sort(unresolved_keys_.begin(), unresolved_keys_.end());
  stats_.unresolved += static_cast<uint64_t>(
      std::unique(unresolved_keys_.begin(), unresolved_keys_.end()) - unresolved_keys_.begin());
}

namespace {

// Lanes of a parallel top-down refinement (Lanes::owner is a byte).
constexpr size_t kMaxLanes = 64;

// A quad's work in the last frame that refined it on this thread with an
// executor: its triangles (about proportional to the criteria evaluated),
// for dealing the next frame's quads out to lanes.
thread_local std::unordered_map<geo::TileKey, uint32_t, geo::TileKeyHash> last_work;

// Deals the quads out to `count` lanes, heaviest first to the lane with the
// least work so far (by the last frame's work; a quad new to the view counts
// as the mean), so that the lanes end together.
std::vector<uint8_t> deal(const Selection& selection, size_t count) {
  const size_t n = selection.quads.size();
  std::vector<double> work(n, -1);
  double known = 0;
  size_t found = 0;
  for (size_t i = 0; i < n; ++i) {
    if (auto it = last_work.find(selection.quads[i].key); it != last_work.end()) {
      work[i] = it->second + 1.0;
      known += work[i];
      ++found;
    }
  }
  const double mean = found ? known / static_cast<double>(found) : 1.0;
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) {
    if (work[i] < 0) work[i] = mean;
    order[i] = static_cast<uint32_t>(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return work[a] > work[b]; });
  std::vector<double> load(count, 0.0);
  std::vector<uint8_t> owner(n);
  for (const uint32_t i : order) {
    const size_t lane =
        static_cast<size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    owner[i] = static_cast<uint8_t>(lane);
    load[lane] += work[i];
  }
  return owner;
}

}  // namespace

// The CPU time of the calling thread.
double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

// Lanes for a top-down refinement: one per thread of the executor, at most
// one per quad.
size_t lane_count(const RefineOptions& o, const Selection& selection) {
  if (!o.executor || o.variant != RefineVariant::kTopDown) return 1;
  return std::min<size_t>({o.executor->concurrency(), selection.quads.size(), kMaxLanes});
}

// This frame's work per quad, for deal() in a later frame.
void remember_work(const Selection& selection, const RefinedMesh& mesh) {
  last_work.clear();
  for (size_t i = 0; i < selection.quads.size(); ++i) {
    last_work[selection.quads[i].key] = mesh.quads[i].index_count / 3;
  }
}

// Lanes (Refiner::lane): quads dealt out by their work (deal(); a split
// crosses to another lane only on a quad's side), refined in rounds until no
// split is left in any inbox, then each lane's quads emitted by the lane. The
// mesh is the one a single refiner makes: a mark ends split exactly when a
// criterion over the threshold or a forced split reaches it, whatever the
// order (top_down()). `cpu`: the CPU time of the lanes' threads other than
// the calling one.
RefinedMesh refine_in_lanes(Refiner& r, const Selection& selection, size_t count,
                            Executor& executor, double& cpu_seconds) {
  // Kept for this thread's next frame (allocated once, not faulted in again).
  // (The lanes' threads name them through references: a thread_local named in
  // a lambda is the running thread's.)
  thread_local std::vector<MarkBlocks> kept_blocks;
  thread_local std::vector<std::vector<uint32_t>> kept_indices;
  std::vector<MarkBlocks>& blocks = kept_blocks;
  std::vector<std::vector<uint32_t>>& indices = kept_indices;
  if (blocks.size() < count) blocks.resize(count);
  if (indices.size() < count) indices.resize(count);
  Lanes lanes;
  lanes.owner = deal(selection, count);
  for (size_t i = 0; i < count; ++i) lanes.inboxes.push_back(std::make_unique<Lanes::Inbox>());
  r.seed_top_down();
  std::vector<Refiner> lane;
  lane.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    blocks[i].reset();
    lane.push_back(r.lane(lanes, static_cast<uint32_t>(i), blocks[i]));
  }
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<double> cpu(count, 0.0);
  const auto pending = [&] {
    return std::any_of(lanes.inboxes.begin(), lanes.inboxes.end(),
                       [](const auto& in) { return in->any.load(); });
  };
  const auto in_lanes = [&](const std::function<void(size_t)>& body) {
    executor.parallel_for(count, [&](size_t i) {
      const double start = thread_cpu_seconds();
      body(i);
      if (std::this_thread::get_id() != caller) cpu[i] += thread_cpu_seconds() - start;
    });
  };
  bool first = true;
  while (first || pending()) {
    first = false;
    in_lanes([&](size_t i) { lane[i].run_lane(); });
  }
  std::vector<RefinedQuad> at(selection.quads.size());
  in_lanes([&](size_t i) { lane[i].emit_lane(indices[i], at); });
  for (const Refiner& l : lane) r.merge(l);
  r.count_unresolved();
  cpu_seconds = 0;
  for (double c : cpu) cpu_seconds += c;
  return r.gather(lanes, indices, at);
}

}  // namespace relief::lod::refinement
