// Heidrich & Seidel 1999, section 4.5: glossy reflection from the prefiltered Phong map (Eq. 9, the exponent
// the environment source was made with) at the normal-map normal's reflection vector, and the diffuse map:
//   colour = ks G(r) + kd albedo (D(n) + sum_i E_i (n.l_i) / pi) + the dynamic lights' specular term +
//   emissive.
#ifndef HEMI_TECHNIQUE_ENV_GLOSSY_GLSL
#define HEMI_TECHNIQUE_ENV_GLOSSY_GLSL
#include "hemi/surface/environment.glsl"
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=8 name=env_glossy
vec3 hemi_technique_env_glossy(HemiSurface s)
{
    const vec3 r = hemi_reflect(s.n, s.v);
    return hemi_env_ks() * hemi_env_glossy(s.position, r) +
           hemi_env_kd() * s.albedo * (hemi_env_diffuse(s.position, s.n) + hemi_env_lambert(s)) +
           hemi_dynamic_specular(s, s.n) + s.emissive;
}

#endif
