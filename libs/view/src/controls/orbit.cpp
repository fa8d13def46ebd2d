// Globe/orbit: the left button drags the view round the point picked under
// the cursor, the wheel zooms toward the point under the cursor (it stays
// under it), keys pan at a speed proportional to the height above the ground
// and turn, tilt and zoom about the point at the centre of the view.
#include <algorithm>
#include <cmath>

#include "base.h"
#include "modes.h"
#include "relief/geo/ellipsoid.h"
#include "relief/view/ground.h"

namespace relief::view::controls {
namespace {

using lod::Vec3;

constexpr double kDragDegPerPixel = 0.25;
constexpr double kZoomPerNotch = 0.8;  // eye distance to the point, per wheel notch in
constexpr double kPanRate = 1.0;       // heights above ground per second
constexpr double kZoomRate = 1.0;      // e-foldings of the distance per second
constexpr double kTurnRate = 60;       // degrees per second
constexpr double kTiltRate = 45;       // degrees per second
constexpr double kMinPitch = -89.5, kMaxPitch = 10;
constexpr double kMaxHeight = 5e7;  // metres: the whole Earth in view

class Orbit final : public ControllerBase {
 public:
  using ControllerBase::ControllerBase;
  ControlMode mode() const override { return ControlMode::orbit; }

 private:
  void on_event(const InputEvent& e, const Ground& ground) override {
    using T = InputEvent::Type;
    if (e.type == T::mouse_down && e.button == MouseButton::left) {
      pivot_ = pivot_at(cursor_x_, cursor_y_, ground);
    } else if (e.type == T::cursor && pressed(MouseButton::left)) {
      orbit_about(pivot_, (e.x - cursor_x_) * kDragDegPerPixel * kDeg,
                  -(e.y - cursor_y_) * kDragDegPerPixel * kDeg);
    } else if (e.type == T::scroll && e.y != 0) {
      zoom_toward(cursor_x_, cursor_y_, std::pow(kZoomPerNotch, e.y), ground);
    }
  }

  void step(double dt, const Ground& ground) override {
    const bool shift = held(Key::shift);
    const int ahead = shift ? axis(Key::w, Key::s) : axis(Key::up, Key::down, Key::w, Key::s);
    const int side = shift ? axis(Key::d, Key::a) : axis(Key::right, Key::left, Key::d, Key::a);
    if (ahead || side) {
      const double v = kPanRate * height_above(ground) * dt;
      camera_ = move_level(camera_, ahead * v, side * v);
    }
    const int turn =
        std::clamp(axis(Key::q, Key::e) + (shift ? axis(Key::left, Key::right) : 0), -1, 1);
    const int tilt = shift ? axis(Key::up, Key::down) : 0;
    const double cx = camera_.width / 2.0, cy = camera_.height_px / 2.0;
    if (turn || tilt) {
      orbit_about(pivot_at(cx, cy, ground), turn * kTurnRate * kDeg * dt,
                  tilt * kTiltRate * kDeg * dt);
    }
    const int zoom = axis(Key::page_up, Key::page_down, Key::plus, Key::minus);
    if (zoom) zoom_toward(cx, cy, std::exp(-zoom * kZoomRate * dt), ground);
  }

  double height_above(const Ground& ground) const {
    return std::max(camera_.height - ground_or_zero(ground, camera_.lon, camera_.lat),
                    options_.clearance);
  }

  // The terrain point under pixel (x, y), else the one at the centre, else
  // the eye itself (the view turns in place).
  Vec3 pivot_at(double x, double y, const Ground& ground) const {
    auto p = pick(camera_, x, y, ground);
    if (!p) p = pick(camera_, camera_.width / 2.0, camera_.height_px / 2.0, ground);
    return p ? lod::ecef(p->lon, p->lat, p->height)
             : lod::ecef(camera_.lon, camera_.lat, camera_.height);
  }

  // Turns the eye and the view together about `pivot`: `yaw` radians about
  // the pivot's up (counterclockwise seen from above: the heading decreases),
  // `tilt` radians about the view's level right (> 0 lowers the eye); the
  // tilt is dropped where it would pass the pitch limits. Roll stays 0.
  void orbit_about(const Vec3& pivot, double yaw, double tilt) {
    const geo::Geodetic g = geo::to_geodetic({pivot.x, pivot.y, pivot.z});
    const Vec3 up = lod::up_at(g.lon_deg, g.lat_deg);
    lod::Camera level = camera_;
    level.roll = 0;
    const Frame f = frame_of(level);
    auto turned = [&](double tilt_angle) {
      const Vec3 axis = lod::normalize(lod::cross(f.forward, up));  // level right
      auto r = [&](const Vec3& v) { return rotate(rotate(v, axis, tilt_angle), up, yaw); };
      lod::Camera c = with_frame(camera_, pivot + r(f.eye - pivot), r(f.forward), r(f.up));
      c.roll = 0;
      return c;
    };
    lod::Camera c = turned(tilt);
    if (tilt != 0 && (c.pitch < kMinPitch || c.pitch > kMaxPitch)) c = turned(0);
    camera_ = c;
  }

  // Scales the eye's distance to the point under pixel (x, y) by `scale`,
  // the view's direction unchanged, so the point stays under the pixel. Over
  // sky, moves along the pixel's ray by the height above the ground instead.
  void zoom_toward(double x, double y, double scale, const Ground& ground) {
    const Frame f = frame_of(camera_);
    Vec3 eye;
    if (auto p = pick(camera_, x, y, ground)) {
      const Vec3 target = lod::ecef(p->lon, p->lat, p->height);
      scale = std::max(scale, options_.clearance / std::max(p->distance, 1e-9));
      eye = target + (f.eye - target) * scale;
    } else {
      const auto view = lod::make_view(camera_);
      if (!view) return;
      const double nx = 2 * x / camera_.width - 1, ny = 1 - 2 * y / camera_.height_px;
      const Vec3 ray = lod::normalize(f.forward + f.right * (nx * view->tan_half_x) +
                                      f.up * (ny * view->tan_half_y));
      eye = f.eye + ray * ((1 - scale) * height_above(ground));
    }
    const lod::Camera c = with_frame(camera_, eye, f.forward, f.up);
    if (c.height <= kMaxHeight) camera_ = c;
  }

  Vec3 pivot_;
};

}  // namespace

std::unique_ptr<Controller> make_orbit(const lod::Camera& start, const ControllerOptions& options) {
  return std::make_unique<Orbit>(start, options);
}

}  // namespace relief::view::controls
