// The base colour factor alone: no texture, no coefficient (the compiler drops the fetches whose results
// this ignores). hemi-bench measures the other techniques against it; also a debug view.
#ifndef HEMI_TECHNIQUE_CONSTANT_GLSL
#define HEMI_TECHNIQUE_CONSTANT_GLSL
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=1 name=constant
vec3 hemi_technique_constant(HemiSurface s)
{
    return s.base_color_factor;
}

#endif
