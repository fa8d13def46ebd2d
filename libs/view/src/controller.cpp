// PLACEHOLDER until the control modes land: every mode holds the camera still
// except playback, which follows its path.
#include "relief/view/controller.h"

namespace relief::view {
namespace {

class HoldStill final : public Controller {
 public:
  HoldStill(ControlMode mode, const lod::Camera& start, const ControllerOptions& options)
      : mode_(mode), camera_(start), path_(options.path) {}
  ControlMode mode() const override { return mode_; }
  void push(const InputEvent&) override {}
  const lod::Camera& update(double dt, const Ground&) override {
    time_ += dt;
    if (mode_ == ControlMode::playback && !path_.empty()) {
      const lod::Camera c = lod::camera_at(path_, path_.front().time + time_);
      camera_.lon = c.lon, camera_.lat = c.lat, camera_.height = c.height;
      camera_.heading = c.heading, camera_.pitch = c.pitch, camera_.roll = c.roll;
    }
    return camera_;
  }
  const lod::Camera& camera() const override { return camera_; }
  void set_camera(const lod::Camera& camera) override { camera_ = camera; }
  double linear_speed() const override { return 0; }
  double angular_speed() const override { return 0; }
  bool finished() const override {
    return mode_ == ControlMode::playback &&
           (path_.empty() || path_.front().time + time_ >= path_.back().time);
  }

 private:
  ControlMode mode_;
  lod::Camera camera_;
  std::vector<lod::Keyframe> path_;
  double time_ = 0;
};

}  // namespace

std::optional<ControlMode> parse_control_mode(std::string_view name) {
  for (ControlMode m : {ControlMode::orbit, ControlMode::aircraft, ControlMode::walk,
                        ControlMode::motorbike, ControlMode::playback}) {
    if (to_string(m) == name) return m;
  }
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
  return std::make_unique<HoldStill>(mode, start, options);
}

}  // namespace relief::view
