// The control modes by name; each mode is one file in controls/.
#include "relief/view/controller.h"

#include "controls/modes.h"

namespace relief::view {

std::optional<ControlMode> parse_control_mode(std::string_view name) {
  for (ControlMode m : {ControlMode::orbit, ControlMode::aircraft, ControlMode::walk,
                        ControlMode::motorbike, ControlMode::playback}) {
    if (to_string(m) == name) return m;
  }
  if (name == "globe") return ControlMode::orbit;
  return std::nullopt;
}

std::string_view to_string(ControlMode mode) {
  switch (mode) {
    case ControlMode::orbit:
      return "orbit";
    case ControlMode::aircraft:
      return "aircraft";
    case ControlMode::walk:
      return "walk";
    case ControlMode::motorbike:
      return "motorbike";
    case ControlMode::playback:
      return "playback";
  }
  return "?";
}

std::unique_ptr<Controller> make_controller(ControlMode mode, const lod::Camera& start,
                                            const ControllerOptions& options) {
  switch (mode) {
    case ControlMode::orbit:
      return controls::make_orbit(start, options);
    case ControlMode::aircraft:
      return controls::make_aircraft(start, options);
    case ControlMode::walk:
      return controls::make_walk(start, options);
    case ControlMode::motorbike:
      return controls::make_motorbike(start, options);
    case ControlMode::playback:
      return controls::make_playback(start, options);
  }
  return nullptr;
}

}  // namespace relief::view
