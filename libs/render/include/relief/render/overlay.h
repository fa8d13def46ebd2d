#pragma once
// Lines drawn over a finished frame in pixel coordinates, without depth
// test: the detector's hints (circles, axis crosses, PSLR bars) and other
// annotations that must stay visible over the terrain.
//
// Uses the GL context current on the calling thread; call from that thread only.
#include <array>
#include <cstdint>
#include <memory>
#include <span>

#include "relief/base/result.h"
#include "relief/render/render_target.h"

namespace relief::render {

struct OverlayLine {
  float x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixels, (0, 0) the top left corner
  std::array<uint8_t, 4> rgba = {255, 255, 255, 255};
};

class Overlay {
 public:
  // Needs a current GL 4.5 core context.
  static Result<std::unique_ptr<Overlay>> create();
  virtual ~Overlay() = default;
  // Draws `lines` over what `target` holds (the target's whole viewport).
  virtual Status draw(std::span<const OverlayLine> lines, RenderTarget& target) = 0;
};

}  // namespace relief::render
