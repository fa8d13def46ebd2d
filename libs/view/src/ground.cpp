// PLACEHOLDER until the ground query and picking land.
#include "relief/view/ground.h"

namespace relief::view {

Ground resident_ground(Scene&) {
  return [](double, double) -> std::optional<double> { return std::nullopt; };
}

std::optional<Pick> pick(const lod::Camera&, double, double, const Ground&) {
  return std::nullopt;
}

}  // namespace relief::view
