#pragma once
// The panels of draw-time processing: one per texture layer (opacity, range,
// colour map, every operator parameter as a slider over its valid range; a
// change shows in the next frame) and the detector's targets (the analysis of
// the hint under the cursor).
#include "viewer_state.h"

namespace relief::window {

void texture_layer_panels(Viewer::Impl& v);
void target_panel(Viewer::Impl& v);

}  // namespace relief::window
