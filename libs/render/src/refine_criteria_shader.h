#pragma once

namespace relief::render {

// The compute shader of GlRefineCriteria (refine_criteria_shader.cpp).
extern const char* const kRefineCriteriaShader;

}  // namespace relief::render
