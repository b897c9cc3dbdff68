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

// World point p in the environment's frame.
vec3 hemi_env_point(vec3 world_p)
{
    return hemi_env_direction(world_p) +
           vec3(environment.world_to_env[0].w, environment.world_to_env[1].w, environment.world_to_env[2].w);
}

// A parabolic map of the environment towards world direction world_d, seen from world point p: a sky's
// (EnvironmentUniforms::tables.z == 0) along the direction alone; reflection probes' box-projected each
// (hemi_box_projected_direction), blended by their boxes' influence at p over its sum (probe k's halves in
// layers 2k and 2k + 1), probe 0 alone where no box holds p. `project`: false for the diffuse map, looked up
// along the normal.
vec3 hemi_env_probes(sampler2DArray map, float extent, vec3 world_p, vec3 world_d, bool project)
{
    const vec3 d = hemi_env_direction(world_d);
    const int count = int(environment.tables.z);
    if (count == 0)
        return hemi_parabolic_lookup(map, extent, d);
    const vec3 p = hemi_env_point(world_p);
    vec3 sum = vec3(0.0);
    float total = 0.0;
    for (int k = 0; k < count; ++k)
    {
        const float w =
            count == 1 ? 1.0
                       : hemi_box_influence(p, environment.probe_box_min[k].xyz,
                                            environment.probe_box_max[k].xyz, environment.probe_centre[k].w);
        if (w <= 0.0)
            continue;
        const vec3 r = project ? hemi_box_projected_direction(p, d, environment.probe_box_min[k].xyz,
                                                              environment.probe_box_max[k].xyz,
                                                              environment.probe_centre[k].xyz)
                               : d;
        vec3 coord = hemi_parabolic_coord(r, extent);
        coord.z += float(2 * k);
        sum += w * texture(map, coord).rgb;
        total += w;
    }
    if (total > 0.0)
        return sum / total;
    const vec3 r = project ? hemi_box_projected_direction(p, d, environment.probe_box_min[0].xyz,
                                                          environment.probe_box_max[0].xyz,
                                                          environment.probe_centre[0].xyz)
                           : d;
    return hemi_parabolic_lookup(map, extent, r);
}

vec3 hemi_env_mirror(vec3 world_p, vec3 world_d)
{
    return hemi_env_probes(env_mirror, environment.extents.x, world_p, world_d, true);
}
vec3 hemi_env_glossy(vec3 world_p, vec3 world_d)
{
    return hemi_env_probes(env_glossy, environment.extents.y, world_p, world_d, true);
}
vec3 hemi_env_diffuse(vec3 world_p, vec3 world_n)
{
    return hemi_env_probes(env_diffuse, environment.extents.z, world_p, world_n, false);
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
vec3 hemi_env_diffuse(vec3 p, vec3 n)
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
