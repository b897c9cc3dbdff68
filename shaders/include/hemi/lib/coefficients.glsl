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

// The cubic B-spline's lookup as two linear ones per axis (Sigg and Hadwiger, GPU Gems 2, ch. 20): at `t` in
// texel units (texel i's centre at i + 0.5), the four texels around t weighted w0..w3 equal two linear
// lookups at `at` (texel units), weighted `weight`. The B-spline smooths (it does not pass through the
// texels) and its result has a continuous first derivative across texel borders, where the linear lookup's
// has a crease.
void hemi_bspline_taps(float t, out vec2 at, out vec2 weight)
{
    const float i = floor(t - 0.5);
    const float f = t - 0.5 - i;
    const float f2 = f * f, f3 = f2 * f;
    const float w0 = (1.0 - 3.0 * f + 3.0 * f2 - f3) / 6.0;
    const float w1 = (4.0 - 6.0 * f2 + 3.0 * f3) / 6.0;
    const float w2 = (1.0 + 3.0 * f + 3.0 * f2 - 3.0 * f3) / 6.0;
    const float w3 = f3 / 6.0;
    weight = vec2(w0 + w1, w2 + w3); // each at least 1/6
    at = vec2(i - 1.0 + w1 / weight.x, i + 1.0 + w3 / weight.y) + 0.5;
}

// hemi_lightmap_coefficients with the cubic B-spline instead of the linear filter: four linear lookups per
// layer instead of one (docs/glsl.md). The maps' sampler clamps to the edge, as for the linear lookup, and a
// UV past the atlas reads what its edge reads (as the paged lookup does).
void hemi_lightmap_coefficients_bicubic(sampler2DArray maps, vec2 uv, int k, out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    const vec2 size = vec2(textureSize(maps, 0).xy);
    const vec2 t = clamp(uv, 0.0, 1.0) * size;
    vec2 x, wx, y, wy;
    hemi_bspline_taps(t.x, x, wx);
    hemi_bspline_taps(t.y, y, wy);
    vec4 packed[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed[i] = vec4(0.0);
    HEMI_UNROLL for (int j = 0; j < 4; ++j)
    {
        const vec2 at = vec2(x[j & 1], y[j >> 1]) / size;
        const float w = wx[j & 1] * wy[j >> 1];
        HEMI_UNROLL for (int i = 0; i < 7; ++i) if (i < hemi_lightmap_layers(k)) packed[i] +=
            w * textureLod(maps, vec3(at, float(i)), 0.0);
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
// One linear lookup of a paged lightmap's packed layers at `t` in atlas texels (clamped to the atlas), times
// `w`, added to `packed`: its page found in the table, the slot's texels read (a page not stored adds 0).
void hemi_paged_lightmap_add(sampler2DArray pages, usampler2D page_table, vec2 atlas, float scale, vec2 t,
                             int k, float w, inout vec4 packed[7])
{
    t = clamp(t, vec2(0.0), atlas);
    const ivec2 page_count = (ivec2(atlas) + HEMI_LIGHTMAP_PAGE - 1) / HEMI_LIGHTMAP_PAGE;
    const ivec2 page = clamp(ivec2(floor(t / float(HEMI_LIGHTMAP_PAGE))), ivec2(0), page_count - 1);
    const int slot = int(texelFetch(page_table, page, 0).r) - 1;
    if (slot < 0)
        return;
    const ivec3 size = textureSize(pages, 0);
    const int per_row = max(1, size.x / HEMI_LIGHTMAP_SLOT);
    const vec2 origin = vec2(ivec2(slot % per_row, slot / per_row) * HEMI_LIGHTMAP_SLOT + 1);
    const vec2 at = (origin + t - vec2(page * HEMI_LIGHTMAP_PAGE)) / vec2(size.xy);
    HEMI_UNROLL for (int i = 0; i < 7; ++i) if (i < hemi_lightmap_layers(k)) packed[i] +=
        (w * scale) * textureLod(pages, vec3(at, float(i)), 0.0);
}

// The atlas's W x H and the stored values' scale, from the page table's last row.
void hemi_page_table_header(usampler2D page_table, out vec2 atlas, out float scale)
{
    const int last = textureSize(page_table, 0).y - 1;
    atlas = vec2(float(texelFetch(page_table, ivec2(0, last), 0).r),
                 float(texelFetch(page_table, ivec2(1, last), 0).r));
    scale = uintBitsToFloat(texelFetch(page_table, ivec2(2, last), 0).r);
}

void hemi_lightmap_coefficients(sampler2DArray pages, usampler2D page_table, vec2 uv, int k,
                                out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    vec2 atlas;
    float scale;
    hemi_page_table_header(page_table, atlas, scale);
    vec4 packed[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed[i] = vec4(0.0);
    hemi_paged_lightmap_add(pages, page_table, atlas, scale, clamp(uv, 0.0, 1.0) * atlas, k, 1.0, packed);
    hemi_unpack_coefficients(packed, k, c);
}

// The mixed lights' shadowmask at `uv` (render::TexelCoefficients::shadowmask(): its RGBA8 layer in the same
// slots as the coefficients' pages, read through the same page table, bilinear): channel c is the share of
// the direct light of the mixed light of channel c that reaches the point (hemi-bake lightmap's bake modes;
// docs/lightmaps.md). An engine multiplies each mixed light's direct light by its channel
// (hemi_shadowmask_channel, hemi/lib/lights.glsl). A page not stored reads 0; a lightmap without a mask binds
// one white texel, which reads 1 wherever a page is stored.
vec4 hemi_lightmap_shadowmask(sampler2DArray mask, usampler2D page_table, vec2 uv)
{
    vec2 atlas;
    float scale;
    hemi_page_table_header(page_table, atlas, scale);
    vec4 packed[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed[i] = vec4(0.0);
    hemi_paged_lightmap_add(mask, page_table, atlas, 1.0, clamp(uv, 0.0, 1.0) * atlas, 1, 1.0, packed);
    return packed[0];
}

// The paged lookup with the cubic B-spline: each of its four linear lookups finds its own page, so its
// footprint of 4 x 4 texels may span pages as the linear one's 2 x 2 may.
void hemi_lightmap_coefficients_bicubic(sampler2DArray pages, usampler2D page_table, vec2 uv, int k,
                                        out vec3 c[HEMI_BASIS_MAX_SIZE])
{
    vec2 atlas;
    float scale;
    hemi_page_table_header(page_table, atlas, scale);
    const vec2 t = clamp(uv, 0.0, 1.0) * atlas;
    vec2 x, wx, y, wy;
    hemi_bspline_taps(t.x, x, wx);
    hemi_bspline_taps(t.y, y, wy);
    vec4 packed[7];
    HEMI_UNROLL for (int i = 0; i < 7; ++i) packed[i] = vec4(0.0);
    HEMI_UNROLL for (int j = 0; j < 4; ++j) hemi_paged_lightmap_add(
        pages, page_table, atlas, scale, vec2(x[j & 1], y[j >> 1]), k, wx[j & 1] * wy[j >> 1], packed);
    hemi_unpack_coefficients(packed, k, c);
}

#endif
