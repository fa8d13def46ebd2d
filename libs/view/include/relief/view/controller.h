#pragma once
// The viewer's control modes (seed 000 §2.4): a viewpoint with a speed,
// moved by queued input actions applied at frame rate, kept above the
// terrain. Independent of the window: tests drive a controller with scripted
// InputEvents and a stepped time.
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string_view>

#include "relief/lod/camera.h"
#include "relief/lod/camera_path.h"
#include "relief/view/input.h"

namespace relief::view {

enum class ControlMode : uint8_t { orbit, aircraft, walk, motorbike, playback };

std::optional<ControlMode> parse_control_mode(std::string_view name);
std::string_view to_string(ControlMode mode);

// The best resident elevation at (lon, lat), metres above the ellipsoid;
// nullopt where none is resident (controllers then keep to the ellipsoid).
using Ground = std::function<std::optional<double>(double lon, double lat)>;

struct ControllerOptions {
  double eye_height = 1.8;       // walk: metres above the ground
  double clearance = 1.0;        // every mode: the least height above the ground
  double max_slope_deg = 35;     // walk: steeper ground is not climbed
  double walk_speed = 1.5;       // walk: metres per second (four times that with shift)
  double bike_eye_height = 1.2;  // motorbike: metres above the ground
  double max_bike_speed = 60;    // motorbike: metres per second
  double speed = 0;              // aircraft, motorbike: the speed at the start, m/s
  // playback: the path played (the controller keeps a copy), from time 0 of
  // the controller's own clock (the sum of update() steps).
  std::vector<lod::Keyframe> path;
};

class Controller {
 public:
  virtual ~Controller() = default;
  virtual ControlMode mode() const = 0;
  // Queues an input; it acts at the next update(). (A resize event sets the
  // camera's viewport; the keys each mode uses are in docs/viewer.md.)
  virtual void push(const InputEvent& event) = 0;
  // Applies the queued input and moves the viewpoint by `dt` seconds, never
  // below the ground. Returns the camera of the frame.
  virtual const lod::Camera& update(double dt, const Ground& ground) = 0;
  virtual const lod::Camera& camera() const = 0;
  // Jumps (keeps the mode; speeds reset).
  virtual void set_camera(const lod::Camera& camera) = 0;
  // Linear speed of the viewpoint, metres per second, and angular speed,
  // degrees per second, over the last update (speed-dependent LOD reads them).
  virtual double linear_speed() const = 0;
  virtual double angular_speed() const = 0;
  // playback: the path has ended.
  virtual bool finished() const { return false; }
};

std::unique_ptr<Controller> make_controller(ControlMode mode, const lod::Camera& start,
                                            const ControllerOptions& options = {});

}  // namespace relief::view
