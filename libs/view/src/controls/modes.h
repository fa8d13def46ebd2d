#pragma once
// One factory per control mode (controller.h's make_controller picks).
#include <memory>

#include "relief/view/controller.h"

namespace relief::view::controls {

std::unique_ptr<Controller> make_orbit(const lod::Camera& start, const ControllerOptions& options);
std::unique_ptr<Controller> make_aircraft(const lod::Camera& start,
                                          const ControllerOptions& options);
std::unique_ptr<Controller> make_walk(const lod::Camera& start, const ControllerOptions& options);
std::unique_ptr<Controller> make_motorbike(const lod::Camera& start,
                                           const ControllerOptions& options);
std::unique_ptr<Controller> make_playback(const lod::Camera& start,
                                          const ControllerOptions& options);

}  // namespace relief::view::controls
