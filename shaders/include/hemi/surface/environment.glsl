// The environment source of the material system (HEMI_SOURCE_ENVIRONMENT, set 2;
// render::EnvironmentLighting): Heidrich & Seidel's parabolic maps (math/paraboloid.h's conventions: layer 0
// holds z >= 0, a direction d at (x, y) = d.xy / (1 + |d.z|), texture coordinate ((x / m + 1) / 2, (1 - y /
// m) / 2) for the map's extent m), the Fresnel table and the factored BRDF's tables. In the other variants
// these functions return 0, so that every technique compiles everywhere (the specialization constant drops
// what a pipeline does not use).
#ifndef HEMI_SURFACE_ENVIRONMENT_GLSL
#define HEMI_SURFACE_ENVIRONMENT_GLSL
#include "hemi/shared/surface.h"
#include "hemi/surface/surface_inputs.glsl"

// The dynamic lights' irradiance over pi at the normal: sum_i E_i max(0, n.l_i) / pi.
vec3 hemi_env_lambert(HemiSurface s)
{
    vec3 sum = vec3(0.0);
    for (int i = 0; i < s.lights; ++i)
        sum += s.e[i] * max(dot(s.n, s.l[i]), 0.0);
    return sum / kHemiPi;
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
    return vec3(dot(environment.world_to_env[0].xyz, world), dot(environment.world_to_env[1].xyz, world),
                dot(environment.world_to_env[2].xyz, world));
}

// Where direction d (environment frame, unit) sits in a parabolic map of extent m: (u, v, layer). The two
// halves agree on the circle (d.z = 0), so u, v and their screen derivatives (the mip level) are continuous
// across the seam.
vec3 hemi_parabolic_coord(vec3 d, float m)
{
    const vec2 xy = d.xy / (1.0 + abs(d.z));
    return vec3(0.5 * (xy.x / m + 1.0), 0.5 * (1.0 - xy.y / m), d.z >= 0.0 ? 0.0 : 1.0);
}

vec3 hemi_env_mirror(vec3 world_d)
{
    return texture(env_mirror, hemi_parabolic_coord(hemi_env_direction(world_d), environment.extents.x)).rgb;
}
vec3 hemi_env_glossy(vec3 world_d)
{
    return texture(env_glossy, hemi_parabolic_coord(hemi_env_direction(world_d), environment.extents.y)).rgb;
}
vec3 hemi_env_diffuse(vec3 world_n)
{
    return texture(env_diffuse, hemi_parabolic_coord(hemi_env_direction(world_n), environment.extents.z)).rgb;
}
// F(cos theta) from the table's row for the material's index of refraction (samples at i / (N - 1)).
float hemi_env_fresnel(float c)
{
    const float n = environment.tables.y;
    return texture(env_fresnel, vec2((clamp(c, 0.0, 1.0) * (n - 1.0) + 0.5) / n, environment.material.z)).r;
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
vec3 hemi_env_mirror(vec3 d)
{
    return vec3(0.0);
}
vec3 hemi_env_glossy(vec3 d)
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
