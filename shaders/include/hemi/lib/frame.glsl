// hemi's GLSL library: tangent frames, normal maps and normal matrices, with glTF's conventions (the ones
// hemi's bakes use: coefficients in the tangent frame are expressed in (T, B, N) with B = cross(N, T) w).
// Plain functions over values the engine supplies; no descriptors. docs/glsl.md.
#ifndef HEMI_LIB_FRAME_GLSL
#define HEMI_LIB_FRAME_GLSL

struct HemiTangentFrame
{
    vec3 t; // unit tangent: the normal map's +u
    vec3 b; // unit bitangent: the normal map's +v as glTF defines it, cross(n, t) * sign(w)
    vec3 n; // unit geometric (interpolated) normal
};

// The tangent frame at a pixel from the interpolated vertex normal and glTF tangent (xyz, w = handedness):
// T re-orthogonalised against N; a degenerate tangent (zero, or parallel to N) falls back to any frame about
// N, so that directions expressed in it stay finite. `normal` need not be unit.
HemiTangentFrame hemi_tangent_frame(vec3 normal, vec4 tangent)
{
    HemiTangentFrame f;
    f.n = normalize(normal);
    vec3 t = tangent.xyz - f.n * dot(f.n, tangent.xyz);
    if (dot(t, t) < 1e-12)
        t = abs(f.n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) - f.n * f.n.x : vec3(0.0, 1.0, 0.0) - f.n * f.n.y;
    f.t = normalize(t);
    f.b = cross(f.n, f.t) * (tangent.w < 0.0 ? -1.0 : 1.0);
    return f;
}

// A world (or object) vector in the frame's coordinates, and back.
vec3 hemi_to_tangent(HemiTangentFrame f, vec3 v)
{
    return vec3(dot(f.t, v), dot(f.b, v), dot(f.n, v));
}
vec3 hemi_from_tangent(HemiTangentFrame f, vec3 v)
{
    return f.t * v.x + f.b * v.y + f.n * v.z;
}

// The tangent-space normal of a normal-map texel as sampled (UNORM, [0, 1]), with glTF's normalTexture.scale
// applied to x and y: normalize((2 texel - 1) * (scale, scale, 1)).
vec3 hemi_normal_map_normal(vec3 texel, float scale)
{
    const vec3 nt = texel * 2.0 - 1.0;
    return normalize(vec3(nt.xy * scale, nt.z));
}

// A vertex's clip-space position and its world position (out), exactly as every pipeline of hemi's material
// system computes them: `model` then `view_projection`, each product `precise` so that no compiler contracts
// it differently in another pipeline. An engine's vertex shader that calls it with the same matrices and
// position gets the same depth to the bit, so its colour pass can test EQUAL against hemi's depth prepass
// (and hemi's against the engine's).
vec4 hemi_clip_position(mat4 view_projection, mat4 model, vec3 position, out vec3 world_position)
{
    precise const vec4 world = model * vec4(position, 1.0);
    precise const vec4 clip = view_projection * world;
    world_position = world.xyz;
    return clip;
}

// The matrix that carries normals through the model matrix's upper 3x3 `m`: the inverse transpose, up to a
// positive scale (the cofactor matrix divided by the sign of the determinant), so that it stays correct under
// non-uniform scale and mirroring. Normalise after interpolation.
mat3 hemi_normal_matrix(mat3 m)
{
    const mat3 cofactor = mat3(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    return determinant(m) < 0.0 ? -cofactor : cofactor;
}

// A glTF tangent through the model matrix's upper 3x3: the direction goes with the surface (m t) and the
// handedness flips when m mirrors, so that cross(N, T) w stays the map's +v.
vec4 hemi_transform_tangent(mat3 m, vec4 tangent)
{
    return vec4(m * tangent.xyz, determinant(m) < 0.0 ? -tangent.w : tangent.w);
}

#endif
