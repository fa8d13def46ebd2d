#pragma once
#include "args.h"
#include "render_setup.h"

namespace relief::cli {

// `relief render --path`: a camera path frame by frame, interactive or complete.
int render_path(const Args& args, RenderSetup& setup);

}  // namespace relief::cli
