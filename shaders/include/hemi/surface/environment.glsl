// The environment source of hemi's own surface shader (HEMI_SOURCE_ENVIRONMENT, set 2;
// render::EnvironmentLighting): its descriptors, and the library's Heidrich & Seidel terms
// (hemi/lib/environment.glsl, which engines call with their own bindings) over them. In the other variants
// these functions return 0, so that every technique compiles everywhere (the specialization constant drops
// what a pipeline does not use).
#ifndef HEMI_SURFACE_ENVIRONMENT_GLSL
#define HEMI_SURFACE_ENVIRONMENT_GLSL
#include "hemi/shared/surface.h"
#include "hemi/surface/surface_inputs.glsl"

// The dynamic lights' irradiance over pi at the normal: sum_i E_i max(0, n.l_i) / pi.
vec3 hemi_env_lambert(HemiSurface s)
{
    return hemi_dynamic_irradiance(s, s.n) / kHemiPi;
}

#if HEMI_SOURCE == HEMI_SOURCE_ENVIRONMENT
layout(set = HEMI_SET_SOURCE, binding = HEMI_ENV_BINDING_UNIFORMS, std140) uniform Environment
{
    EnvironmentUniforms environment;
};
layout(set = HEMI_SET_SOURCE, binding = HEMI_ENV_BINDING_MIRROR) uniform sampler2DArray env_mirror;
layout(set = HEMI_SET_SOURCE, binding = HEMI_ENV_BINDING_GLOSSY) uniform sampler2DArray env_glossy;
layout(set = HEMI_SET_SOURCE, binding = HEMI_ENV_BINDING_DIFFUSE) uniform sampler2DArray env_diffuse;
layout(set = HEMI_SET_SOURCE, binding = HEMI_ENV_BINDING_FRESNEL) uniform sampler2D env_fresnel;
layout(set = HEMI_SET_SOURCE, binding = HEMI_ENV_BINDING_BRDF) uniform sampler2DArray env_brdf;

// A world direction in the environment's frame.
vec3 hemi_env_direction(vec3 world)
{
    return hemi_env_direction(environment.world_to_env[0].xyz, environment.world_to_env[1].xyz,
                              environment.world_to_env[2].xyz, world);
}

// A reflection from world point p along world_d, in the environment's frame: box-projected when the
// environment is a reflection probe (EnvironmentUniforms::probe_centre.w), else the direction alone.
vec3 hemi_env_reflection(vec3 world_p, vec3 world_d)
{
    const vec3 d = hemi_env_direction(world_d);
    if (environment.probe_centre.w == 0.0)
        return d;
    const vec3 p =
        hemi_env_direction(world_p) +
        vec3(environment.world_to_env[0].w, environment.world_to_env[1].w, environment.world_to_env[2].w);
    return hemi_box_projected_direction(p, d, environment.probe_box_min.xyz, environment.probe_box_max.xyz,
                                        environment.probe_centre.xyz);
}

vec3 hemi_env_mirror(vec3 world_p, vec3 world_d)
{
    return hemi_parabolic_lookup(env_mirror, environment.extents.x, hemi_env_reflection(world_p, world_d));
}
vec3 hemi_env_glossy(vec3 world_p, vec3 world_d)
{
    return hemi_parabolic_lookup(env_glossy, environment.extents.y, hemi_env_reflection(world_p, world_d));
}
vec3 hemi_env_diffuse(vec3 world_n)
{
    return hemi_parabolic_lookup(env_diffuse, environment.extents.z, hemi_env_direction(world_n));
}
// F(cos theta) from the table's row for the material's index of refraction.
float hemi_env_fresnel(float c)
{
    return hemi_fresnel_lookup(env_fresnel, environment.tables.y, environment.material.z, c);
}
float hemi_env_kd()
{
    return environment.material.x;
}
float hemi_env_ks()
{
    return environment.material.y;
}
bool hemi_env_coating()
{
    return environment.material.w != 0.0;
}
float hemi_env_table_size()
{
    return environment.tables.x;
}
#define HEMI_ENV_BRDF_TABLES env_brdf
#else
vec3 hemi_env_mirror(vec3 p, vec3 d)
{
    return vec3(0.0);
}
vec3 hemi_env_glossy(vec3 p, vec3 d)
{
    return vec3(0.0);
}
vec3 hemi_env_diffuse(vec3 n)
{
    return vec3(0.0);
}
float hemi_env_fresnel(float c)
{
    return 0.0;
}
float hemi_env_kd()
{
    return 0.0;
}
float hemi_env_ks()
{
    return 0.0;
}
bool hemi_env_coating()
{
    return false;
}
float hemi_env_table_size()
{
    return 2.0;
}
#endif

#endif
