// Irradiance with a GGX coat (docs/specular.md): the irradiance technique (the basis at the normal, the
// dynamic lights, whose specular is exact GGX under the coat) plus the specular the coefficients hold,
// hemi_coefficient_specular (a directional lightmap's or a PRT vertex's dominant sun and the rest's split
// sum; an SH9 probe's over the sphere). The coat's roughness and f0 are the frame's (FrameData::
// glossy_roughness, glossy_f0; roughness 0: no coat, then this is the irradiance technique). Its own
// technique so that only the materials that ask for it compile the estimator.
#ifndef HEMI_TECHNIQUE_GGX_GLSL
#define HEMI_TECHNIQUE_GGX_GLSL
#include "hemi/surface/surface_inputs.glsl"
#include "hemi/techniques/irradiance.glsl"

// hemi-technique: id=10 name=ggx
vec3 hemi_technique_ggx(HemiSurface s)
{
    return hemi_technique_irradiance(s) + hemi_coefficient_specular(s, s.n);
}

#endif
