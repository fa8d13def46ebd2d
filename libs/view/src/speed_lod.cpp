// PLACEHOLDER until speed-dependent LOD lands: the still threshold always.
#include "relief/view/speed_lod.h"

namespace relief::view {

double SpeedLod::threshold(double still_pixels, double, double, double, double) {
  factor_ = 1;
  return still_pixels;
}

}  // namespace relief::view
