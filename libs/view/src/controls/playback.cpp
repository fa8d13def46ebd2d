// Playback: the camera of the path at the controller's own time (the sum of
// the update steps from 0), so a path recorded frame by frame with the same
// steps plays back bit for bit. Field of view and viewport stay the window's.
// A cut is a jump: the frame that crosses it reports no speed.
#include "base.h"
#include "modes.h"

namespace relief::view::controls {
namespace {

class Playback final : public ControllerBase {
 public:
  Playback(const lod::Camera& start, const ControllerOptions& options)
      : ControllerBase(start, options) {
    if (!options_.path.empty()) place();
  }
  ControlMode mode() const override { return ControlMode::playback; }
  bool finished() const override {
    return options_.path.empty() || options_.path.front().time + time_ >= options_.path.back().time;
  }

 private:
  void step(double dt, const Ground&) override {
    if (options_.path.empty()) return;
    const double before = options_.path.front().time + time_;
    time_ += dt;
    const double now = options_.path.front().time + time_;
    for (const lod::Keyframe& k : options_.path) {
      if (k.cut && before < k.time && k.time <= now) jumped_ = true;
    }
    place();
  }
  void place() {
    const lod::Camera c = lod::camera_at(options_.path, options_.path.front().time + time_);
    camera_.lon = c.lon, camera_.lat = c.lat, camera_.height = c.height;
    camera_.heading = c.heading, camera_.pitch = c.pitch, camera_.roll = c.roll;
  }

  double time_ = 0;
};

}  // namespace

std::unique_ptr<Controller> make_playback(const lod::Camera& start,
                                          const ControllerOptions& options) {
  return std::make_unique<Playback>(start, options);
}

}  // namespace relief::view::controls
