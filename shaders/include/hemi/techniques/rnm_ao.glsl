// Green 2007's second baseline: radiosity normal mapping (Listing 1, the rnm technique) with a plain ambient
// occlusion channel, the material's glTF occlusion texture, multiplying the diffuse light (the lightmap's
// and the dynamic lights'): non-directional, so it darkens a crevice whichever way the light comes from,
// where the SSBump map's directional occlusion shadows only the light that the relief blocks.
// colour = occlusion * albedo * E / pi + specular + emissive, E as in the rnm technique.
#ifndef HEMI_TECHNIQUE_RNM_AO_GLSL
#define HEMI_TECHNIQUE_RNM_AO_GLSL
#include "hemi/surface/surface_inputs.glsl"
#include "hemi/techniques/rnm.glsl"

// hemi-technique: id=4 name=rnm_ao
vec3 hemi_technique_rnm_ao(HemiSurface s)
{
    return s.occlusion * s.albedo * hemi_rnm_surface_irradiance(s) / kHemiPi + hemi_dynamic_specular(s, s.n) +
           s.emissive;
}

#endif
