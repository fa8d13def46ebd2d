#pragma once
// What every control mode shares (seed 000 §2.4.3, the Point module): the
// viewpoint, the queue of input applied at the next update, the state of keys,
// buttons and cursor, the collision with the ground and the speeds.
#include <array>
#include <vector>

#include "geometry.h"
#include "relief/view/controller.h"

namespace relief::view::controls {

class ControllerBase : public Controller {
 public:
  ControllerBase(const lod::Camera& start, const ControllerOptions& options)
      : camera_(start), options_(options) {}
  void push(const InputEvent& event) override { queue_.push_back(event); }
  // Applies the queued events in order (on_event), then moves (step), then
  // lifts the viewpoint to the ground + clearance and measures its speeds.
  const lod::Camera& update(double dt, const Ground& ground) final;
  const lod::Camera& camera() const override { return camera_; }
  void set_camera(const lod::Camera& camera) override;
  double linear_speed() const override { return linear_speed_; }
  double angular_speed() const override { return angular_speed_; }

 protected:
  // One event, before the held keys, buttons and cursor take it into account
  // (so a cursor event sees the previous position in cursor_x_, cursor_y_).
  virtual void on_event(const InputEvent& /*event*/, const Ground& /*ground*/) {}
  // Moves the viewpoint by dt seconds under the held keys.
  virtual void step(double dt, const Ground& ground) = 0;
  // A jump (set_camera): the mode's speeds and drags reset.
  virtual void on_jump() {}

  bool held(Key key) const { return keys_[static_cast<size_t>(key)]; }
  bool pressed(MouseButton b) const { return buttons_[static_cast<size_t>(b)]; }
  // +1, -1 or 0 from a pair of keys (either of each pair).
  int axis(Key plus, Key minus, Key plus2 = Key::unknown, Key minus2 = Key::unknown) const;
  double least_height(const Ground& ground, double lon, double lat) const {
    return ground_or_zero(ground, lon, lat) + options_.clearance;
  }

  lod::Camera camera_;
  ControllerOptions options_;
  // Set by a step that jumped (a cut in a path): its speeds are 0, not the
  // jump's.
  bool jumped_ = false;
  double cursor_x_ = 0, cursor_y_ = 0;

 private:
  std::vector<InputEvent> queue_;
  std::array<bool, 64> keys_{};
  static_assert(static_cast<size_t>(Key::f12) < 64);
  std::array<bool, 3> buttons_{};
  double linear_speed_ = 0, angular_speed_ = 0;
};

}  // namespace relief::view::controls
