// hemi's GLSL library: where a surface's K RGB coefficients come from, for the engine's own shaders to fetch
// them from the resources it binds (hemi's runtime objects hand out their views; docs/glsl.md):
//   - a lightmap: K coefficients packed into the RGBA layers of a 2D array image (ceil(3K / 4) layers),
//     sampled (bilinear, clamped) at the lightmap UV (TEXCOORD_1);
//   - a PRT object: its transfer (or CPCA) pass output, an RGBA32F texel buffer holding K texels per vertex,
//     fetched in the vertex stage and interpolated (hemi_pack_coefficients / hemi_unpack_coefficients carry
//     them through 7 vec4 varyings);
//   - a probe or an environment: K RGB values the engine keeps in its own uniform or storage buffer.
// No descriptors; the engine passes its samplers. Unused entries (k >= K) are zero.
#ifndef HEMI_LIB_COEFFICIENTS_GLSL
#define HEMI_LIB_COEFFICIENTS_GLSL
#include "hemi/shared/bases.h"

#ifndef HEMI_UNROLL
#define HEMI_UNROLL // define as [[unroll]] (GL_EXT_control_flow_attributes) before including, if wanted
#endif

// Texels first .. first + k - 1 of a per-vertex source (first = the object's texel offset + vertex * K).
void hemi_vertex_coefficients(samplerBuffer coefficients, int first, int k, out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    HEMI_UNROLL for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
    {
        c[i] = vec3(0.0);
        if (i < k)
            c[i] = texelFetch(coefficients, first + i).rgb;
    }
}

// Up to 9 RGB coefficients (27 floats) in 7 vec4 varyings, and back.
void hemi_pack_coefficients(vec3 c[HEMI_BASIS_MAX_SIZE], out vec4 packed[7])
{
    float f[28];
    HEMI_UNROLL for (int i = 0; i < 28; ++i) f[i] = 0.0;
    HEMI_UNROLL for (int i = 0; i < HEMI_BASIS_MAX_SIZE && i < 9; ++i)
    {
        f[i * 3 + 0] = c[i].r;
        f[i * 3 + 1] = c[i].g;
        f[i * 3 + 2] = c[i].b;
    }
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed[i] =
        vec4(f[i * 4], f[i * 4 + 1], f[i * 4 + 2], f[i * 4 + 3]);
}
void hemi_unpack_coefficients(vec4 packed[7], int k, out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    HEMI_UNROLL for (int i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
    {
        c[i] = vec3(0.0);
        if (i < k && i < 9)
        {
            const int j = i * 3;
            c[i] = vec3(packed[j / 4][j % 4], packed[(j + 1) / 4][(j + 1) % 4],
                        packed[(j + 2) / 4][(j + 2) % 4]);
        }
    }
}

// A lightmap's K RGB coefficients at `uv`, from their packed maps: the K x 3 floats of a texel,
// c0.r c0.g c0.b c1.r ..., fill the RGBA channels of layers 0, 1, ... in order (float f = 3 k + channel is
// channel f % 4 of layer f / 4), so K coefficients take hemi_lightmap_layers(K) = ceil(3K / 4) bilinear
// fetches instead of K. Filtering is linear per channel, so the packed maps filter exactly as K separate
// maps would (render::TexelCoefficients packs them; docs/glsl.md).
int hemi_lightmap_layers(int k)
{
    return (3 * k + 3) / 4;
}
void hemi_lightmap_coefficients(sampler2DArray maps, vec2 uv, int k, out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    vec4 packed[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i)
    {
        packed[i] = vec4(0.0);
        if (i < hemi_lightmap_layers(k))
            packed[i] = texture(maps, vec3(uv, float(i)));
    }
    hemi_unpack_coefficients(packed, k, c);
}

#endif
