#pragma once
// Speed-dependent level of detail (seed 000 §2.4.4): while the view moves,
// the pixel-error threshold relaxes with its angular and linear speed, and
// it returns smoothly to the still threshold when the view stops; the first
// frame after stopping long enough is the complete still's.
namespace relief::view {

struct SpeedLodOptions {
  bool enabled = true;
  double max_factor = 4;      // the relaxed threshold is at most this times the still one
  double angular_scale = 30;  // degrees per second that double the threshold
  double linear_scale =
      1;  // screen heights per second (speed / height above ground) that double it
  double settle_seconds = 0.3;  // time constant of the return when the view stops
};

class SpeedLod {
 public:
  explicit SpeedLod(const SpeedLodOptions& options = {}) : options_(options) {}
  // The threshold for a frame `dt` seconds after the previous one, the view
  // moving at `angular_speed` degrees per second and `linear_speed` m/s at
  // `height_above_ground` metres.
  double threshold(double still_pixels, double dt, double angular_speed, double linear_speed,
                   double height_above_ground);
  double factor() const { return factor_; }

 private:
  SpeedLodOptions options_;
  double factor_ = 1;
};

}  // namespace relief::view
