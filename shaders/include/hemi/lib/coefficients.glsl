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
// maps would (docs/glsl.md).
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

// Paged lightmaps (render::TexelCoefficients): the W x H atlas is cut into pages of HEMI_LIGHTMAP_PAGE^2
// (hemi/shared/bases.h)
// texels and only the pages that hold texels are stored, each in a slot of HEMI_LIGHTMAP_SLOT^2 texels of the
// packed maps (`pages`, slots row after row) with a border of one texel copied from the neighbouring pages
// (the atlas's edge texels at its edge), so a bilinear lookup anywhere in a page stays in its slot. The page
// table (R32_UINT, max(3, ceil(W / PAGE)) x (ceil(H / PAGE) + 1)) holds each page's slot + 1, 0 for a page
// that is not stored (it reads as 0), and in its last row the atlas's W and H (texels 0 and 1) and the bits
// of the float scale the stored values are multiplied by (texel 2: a power of two, 1 unless the light's
// magnitude needed another to fit half floats, io/half_scale.h). The lookup is
// the packed maps' bilinear lookup of the whole atlas with the edge clamped, from memory that follows the
// covered texels, for atlases past the device's largest image.
void hemi_lightmap_coefficients(sampler2DArray pages, usampler2D page_table, vec2 uv, int k,
                                out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    const ivec2 table = textureSize(page_table, 0);
    const vec2 atlas = vec2(float(texelFetch(page_table, ivec2(0, table.y - 1), 0).r),
                            float(texelFetch(page_table, ivec2(1, table.y - 1), 0).r));
    const vec2 t = clamp(uv, 0.0, 1.0) * atlas;
    const ivec2 page_count = (ivec2(atlas) + HEMI_LIGHTMAP_PAGE - 1) / HEMI_LIGHTMAP_PAGE;
    const ivec2 page = clamp(ivec2(floor(t / float(HEMI_LIGHTMAP_PAGE))), ivec2(0), page_count - 1);
    const int slot = int(texelFetch(page_table, page, 0).r) - 1;
    const float scale = uintBitsToFloat(texelFetch(page_table, ivec2(2, table.y - 1), 0).r);
    const ivec3 size = textureSize(pages, 0);
    const int per_row = max(1, size.x / HEMI_LIGHTMAP_SLOT);
    const vec2 origin = vec2(ivec2(max(slot, 0) % per_row, max(slot, 0) / per_row) * HEMI_LIGHTMAP_SLOT + 1);
    const vec2 at = (origin + t - vec2(page * HEMI_LIGHTMAP_PAGE)) / vec2(size.xy);
    vec4 packed[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i)
    {
        packed[i] = vec4(0.0);
        if (i < hemi_lightmap_layers(k))
            packed[i] = slot < 0 ? vec4(0.0) : textureLod(pages, vec3(at, float(i)), 0.0) * scale;
    }
    hemi_unpack_coefficients(packed, k, c);
}

#endif
