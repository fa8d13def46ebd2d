#include "relief/lod/split_feedback.h"

namespace relief::lod {

namespace {

// The eye's distance to the quad's box, or nothing when it cannot be had.
std::optional<double> eye_distance(const View& view, TerrainModel& terrain,
                                   const geo::TileKey& key) {
  auto info = terrain.quad(key);
  if (!info) return std::nullopt;
  return distance_to((*info)->box, view.eye);
}

}  // namespace

void SplitFeedback::record(const View& view, TerrainModel& terrain, const RefineStats& stats) {
  if (distance_.size() + stats.split_wanted.size() > kMaxQuads) distance_.clear();
  for (const geo::TileKey& key : stats.split_wanted) {
    if (const auto d = eye_distance(view, terrain, key)) distance_[key] = *d;
  }
}

bool SplitFeedback::wanted(const View& view, TerrainModel& terrain, const geo::TileKey& key) {
  const auto it = distance_.find(key);
  if (it == distance_.end()) return false;
  const auto d = eye_distance(view, terrain, key);
  if (d && *d <= 2 * it->second) return true;
  distance_.erase(it);
  return false;
}

std::function<bool(const geo::TileKey&)> SplitFeedback::for_selection(const View& view,
                                                                      TerrainModel& terrain) {
  if (distance_.empty()) return {};
  return [this, &view, &terrain](const geo::TileKey& key) { return wanted(view, terrain, key); };
}

}  // namespace relief::lod
