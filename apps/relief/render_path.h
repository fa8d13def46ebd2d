#pragma once
#include <string>

#include "args.h"
#include "relief/base/clock.h"
#include "render_setup.h"

namespace relief::cli {

// Whether `-o` names a movie (*.mp4) rather than a directory of frames.
bool is_movie_output(const std::string& output);

// `relief render --path`: a camera path frame by frame, interactive or complete.
// Frames are paced and timed on `clock`.
int render_path(const Args& args, RenderSetup& setup, const Clock& clock = steady_clock());

}  // namespace relief::cli
