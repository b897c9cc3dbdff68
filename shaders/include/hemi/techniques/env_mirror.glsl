// Heidrich & Seidel 1999, sections 4.3 and 4.4: mirror reflection of the parabolic environment map at the
// normal-map normal's reflection vector (its mip level from the vector's screen derivatives), weighted by the
// Fresnel table at n.v, and the diffuse map at the normal:
//   colour = F L_m(r) + L_d, or with the coating blend F L_m(r) + (1 - F) L_d, L_d = kd albedo (D(n) +
//   sum_i E_i (n.l_i) / pi); + the dynamic lights' specular term (the frame's Blinn-Phong: the paper's Fig.
//   10, "local Phong illumination plus environment map") + emissive.
#ifndef HEMI_TECHNIQUE_ENV_MIRROR_GLSL
#define HEMI_TECHNIQUE_ENV_MIRROR_GLSL
#include "hemi/surface/environment.glsl"
#include "hemi/surface/surface_inputs.glsl"

// hemi-technique: id=7 name=env_mirror
vec3 hemi_technique_env_mirror(HemiSurface s)
{
    const float nv = dot(s.n, s.v);
    const vec3 r = hemi_reflect(s.n, s.v);
    const float f = hemi_env_fresnel(max(nv, 0.0));
    const vec3 ld = hemi_env_kd() * s.albedo * (hemi_env_diffuse(s.position, s.n) + hemi_env_lambert(s));
    return f * hemi_env_mirror(s.position, r) + (hemi_env_coating() ? 1.0 - f : 1.0) * ld +
           hemi_dynamic_specular(s, s.n) + s.emissive;
}

#endif
