// Paged lightmaps (render::TexelCoefficients, hemi_lightmap_coefficients(pages, page_table, ...)): only the
// 64 x 64-texel pages that hold texels are stored, each in a slot with a one-texel border, and the shader
// finds a lookup's page through the page table. The check: a quad whose TEXCOORD_1 spans a 200 x 130 atlas
// of 4 x 3 pages, one page and scattered blocks left out, coefficients that vary along both axes (and faster
// than linearly along x, so that a lookup one texel off shows): at every drawn pixel the colour equals the
// CPU's bilinear lookup of the same maps (io::BlockMaps::bilinear, the atlas's edge clamped, blocks not
// kept reading 0) at the pixel's UV from the aux attachment. A slot without its border, a page mapped to a
// neighbour's slot or an origin off by a texel draws different colours along the page borders.
#include "../gpu_fixture.h"
#include "engine_pass.h"

#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/block_maps.h>
#include <hemi/math/camera.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/scene/gpu_mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace
{
using namespace hemi;

class PagedLightmap : public test::GpuTest
{
};

constexpr uint32_t kSize = 160, kW = 200, kH = 130;

glm::vec3 value(uint32_t x, uint32_t y)
{
    return glm::vec3(0.2f + 0.6f * float(x) / kW, 0.2f + 0.6f * float(y) / kH,
                     0.5f + 0.3f * std::sin(x / 7.0f));
}
} // namespace

TEST_F(PagedLightmap, LinearAndBicubicLookupsEqualTheAtlasLookupsAcrossPageBorders)
{
    gpu::Device& dev = test::device();
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    target.color_attachments = 2;
    target.aux_output = true;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    io::Mesh quad;
    quad.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    quad.normals.assign(4, glm::vec3(0, -1, 0));
    quad.tangents.assign(4, glm::vec4(1, 0, 0, 1));
    quad.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    quad.uvs1 = quad.uvs;
    quad.indices = {0, 1, 2, 0, 2, 3};
    const render::GpuMesh mesh(dev, quad, upload);
    const io::Material white;
    render::TextureSet textures(dev, std::span<const io::ImageRgba8>(), std::span<const io::Material>(),
                                upload);
    const render::MaterialInstance instance(system, textures, white, upload);

    // Every block but page (1, 1)'s, those of texel columns 120 to 199 (page columns 2 and 3, and the texel
    // beside them) and every seventh of the rest; the plain lightmap (K = 1), pi times the colour a white
    // surface shows.
    const uint32_t bx = (kW + 7) / 8, by = (kH + 7) / 8;
    std::vector<uint32_t> kept;
    for (uint32_t b = 0; b < bx * by; ++b)
    {
        const uint32_t x = b % bx, y = b / bx;
        if ((x / 8 == 1 && y / 8 == 1) || (x >= 15 && x <= 24) || b % 7 == 3)
            continue;
        kept.push_back(b);
    }
    io::BlockMaps maps(io::BlockGrid(kW, kH, kept), 1);
    for (size_t s = 0; s < maps.grid.slots(); ++s)
    {
        const glm::uvec2 t = maps.grid.texel(s);
        if (t.x >= kW || t.y >= kH)
            continue;
        const glm::vec3 v = value(t.x, t.y) * float(M_PI);
        for (int c = 0; c < 3; ++c)
            maps.values[((s / 64) * 64 + s % 64) * 3 + c] = v[c];
    }
    const render::TexelCoefficients atlas(system, maps, upload);
    // Page (1, 1) holds no block but borders blocks of its neighbours (a lookup within half a texel of its
    // edge reads them), so it is stored; page columns 2 and 3 meet no block and are not: 4 x 3 - 6 pages.
    EXPECT_EQ(atlas.stored_pages(), 6u);

    render::FrameSet frame(system);
    render::FrameData f;
    f.view_projection = math::look_at_projection(glm::vec3(0, -2.6f, 0), glm::vec3(0.0f), 45.0f, 1.0f);
    const float clear[4] = {0, 0, 0, 0};
    // The quad drawn with the linear or the bicubic lookup (MaterialKey::lightmap_filter).
    bool uploaded = false;
    auto draw = [&](render::LightmapFilter filter)
    {
        render::MaterialKey key;
        key.source = render::CoefficientSourceKind::Texel;
        key.basis = HEMI_BASIS_VERTEX_IRRADIANCE;
        key.lightmap_filter = filter;
        const render::MaterialType& type = system.type(key);
        gpu::one_shot(dev,
                      [&](VkCommandBuffer cmd)
                      {
                          if (!uploaded)
                              upload.record(cmd);
                          uploaded = true;
                          frame.record_update(cmd, f);
                          pass.begin(cmd, clear);
                          render::DrawBindings b;
                          b.type = &type;
                          b.frame = frame.set();
                          b.material = instance.set();
                          b.source = atlas.set();
                          b.push.model = glm::mat4(1.0f);
                          render::bind_material(cmd, b);
                          mesh.bind(cmd);
                          mesh.draw(cmd, 0, mesh.index_count());
                          vkCmdEndRenderPass(cmd);
                      });
    };
    draw(render::LightmapFilter::Linear);
    const std::vector<float> color = pass.read_color(0), aux = pass.read_color(1);
    int drawn = 0, outside = 0, at_borders = 0;
    double largest = 0.0;
    for (uint32_t y = 0; y < kSize; ++y)
        for (uint32_t x = 0; x < kSize; ++x)
        {
            const size_t p = (size_t(y) * kSize + x) * 4;
            if (aux[p + 3] != 1.0f)
                continue;
            ++drawn;
            const glm::vec2 uv(aux[p], aux[p + 1]);
            const glm::vec3 want = maps.bilinear(0, uv) / float(M_PI);
            const float tx = uv.x * kW, ty = uv.y * kH;
            at_borders += std::abs(tx - std::round(tx / 64) * 64) < 1.0f ||
                          std::abs(ty - std::round(ty / 64) * 64) < 1.0f;
            for (int c = 0; c < 3; ++c)
            {
                const double d = std::abs(double(color[p + c]) - want[c]);
                largest = std::max(largest, d);
                if (d > 2e-3 && outside++ < 8)
                    ADD_FAILURE() << "pixel " << x << "," << y << " (texel " << tx << "," << ty
                                  << ") channel " << c << ": GPU " << color[p + c] << ", CPU " << want[c];
            }
        }
    EXPECT_GT(drawn, 10000);
    EXPECT_GT(at_borders, 300) << "too few pixels look up across a page border";
    EXPECT_EQ(outside, 0);
    std::printf("paged lightmap: %d pixels (%d within a texel of a page border), largest difference %.5f\n",
                drawn, at_borders, largest);

    // The bicubic lookup of the same pages against the cubic B-spline over the atlas's texels (the blocks
    // not kept reading 0, the edge clamped), written out from its four weights per axis.
    draw(render::LightmapFilter::Bicubic);
    const std::vector<float> bicubic = pass.read_color(0), bicubic_aux = pass.read_color(1);
    const std::vector<float> dense = maps.dense();
    auto texel = [&](int64_t x, int64_t y)
    {
        x = std::clamp<int64_t>(x, 0, kW - 1);
        y = std::clamp<int64_t>(y, 0, kH - 1);
        const float* t = &dense[(size_t(y) * kW + size_t(x)) * 3];
        return glm::dvec3(t[0], t[1], t[2]);
    };
    auto weights = [](double t, int64_t& first, double w[4])
    {
        const double i = std::floor(t - 0.5), u = t - 0.5 - i;
        first = int64_t(i) - 1;
        w[0] = (1 - u) * (1 - u) * (1 - u) / 6;
        w[1] = (3 * u * u * u - 6 * u * u + 4) / 6;
        w[2] = (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6;
        w[3] = u * u * u / 6;
    };
    int bicubic_drawn = 0, bicubic_outside = 0;
    double bicubic_largest = 0.0;
    for (size_t p = 0; p < size_t(kSize) * kSize * 4; p += 4)
    {
        if (bicubic_aux[p + 3] != 1.0f)
            continue;
        ++bicubic_drawn;
        int64_t x0, y0;
        double wx[4], wy[4];
        weights(double(std::clamp(bicubic_aux[p], 0.0f, 1.0f)) * kW, x0, wx);
        weights(double(std::clamp(bicubic_aux[p + 1], 0.0f, 1.0f)) * kH, y0, wy);
        glm::dvec3 want(0.0);
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i)
                want += wx[i] * wy[j] * texel(x0 + i, y0 + j);
        want /= M_PI;
        for (int c = 0; c < 3; ++c)
        {
            const double d = std::abs(double(bicubic[p + c]) - want[c]);
            bicubic_largest = std::max(bicubic_largest, d);
            if (d > 2e-3 && bicubic_outside++ < 8)
                ADD_FAILURE() << "bicubic: pixel " << p / 4 << " channel " << c << ": GPU " << bicubic[p + c]
                              << ", CPU " << want[c];
        }
    }
    EXPECT_GT(bicubic_drawn, 10000);
    EXPECT_EQ(bicubic_outside, 0);
    std::printf("paged lightmap, bicubic: %d pixels, largest difference %.5f\n", bicubic_drawn,
                bicubic_largest);
}
