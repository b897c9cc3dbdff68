// The lightmap material (issue 12, "Done when" line 5): a baked lightmap asset drawn by LightmapModel in one
// render pass of the caller's, beside a PRT object, equals at sampled pixels a CPU evaluation of the same
// material: the coefficient maps read bilinearly at TEXCOORD_1 (half floats, as stored), each basis evaluated
// at the normal-map normal, times albedo / pi. The validation layer is on (GpuTest fails on any message).
#include "../gpu_fixture.h"
#include "engine_pass.h"

#include <hemi/bake/lightmap_atlas.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/prt_bake.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/gpu/commands.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/basis.h>
#include <hemi/math/sh.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/prt_model.h>
#include <hemi/render/view/lightmap_view.h>
#include <hemi/render/view/prt_view.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include <cmath>
#include <cstring>

namespace
{

class LightmapMaterial : public hemi::test::GpuTest
{
};

constexpr uint32_t W = 160, H = 96, kAtlas = 16;

// Where pixel (px, py) of a size x size view lands on the plane z = 0: the view's own projection inverted.
glm::vec3 point_on_floor(const glm::mat4& inverse_view_projection, uint32_t size, uint32_t px, uint32_t py)
{
    const glm::vec2 ndc((px + 0.5f) / size * 2.0f - 1.0f, (py + 0.5f) / size * 2.0f - 1.0f);
    const glm::vec4 a = inverse_view_projection * glm::vec4(ndc, 0.0f, 1.0f);
    const glm::vec4 b = inverse_view_projection * glm::vec4(ndc, 1.0f, 1.0f);
    const glm::vec3 p0 = glm::vec3(a) / a.w, p1 = glm::vec3(b) / b.w;
    return p0 + (p1 - p0) * (p0.z / (p0.z - p1.z));
}

// SH9 in hemi's convention, typed from docs/DESIGN.md.
std::array<double, 9> sh9(const glm::dvec3& d)
{
    return {0.282095,
            -0.488603 * d.y,
            0.488603 * d.z,
            -0.488603 * d.x,
            1.092548 * d.x * d.y,
            -1.092548 * d.y * d.z,
            0.315392 * (3 * d.z * d.z - 1),
            -1.092548 * d.x * d.z,
            0.546274 * (d.x * d.x - d.y * d.y)};
}

// A floor z = 0 over [-1, 1]^2 in hemi's world (4 x 4 quads), lightmap UVs over [0, 1]^2 and normal-map UVs
// twice that (so a shader reading the wrong UV set samples the wrong coefficients); a tilted 1x1 normal map
// and a coloured base.
hemi::io::LightmapAsset floor_asset(const std::vector<std::string>& outputs, glm::vec3& albedo,
                                    glm::vec3& normal, const uint8_t* normal_texel = nullptr,
                                    bool furnace = false)
{
    hemi::io::LightmapAsset a;
    hemi::io::Mesh& m = a.mesh;
    const int cells = 4;
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i)
        {
            const uint32_t base = uint32_t(m.positions.size());
            const glm::vec2 c[4] = {{float(i) / cells, float(j + 1) / cells},
                                    {float(i + 1) / cells, float(j + 1) / cells},
                                    {float(i + 1) / cells, float(j) / cells},
                                    {float(i) / cells, float(j) / cells}};
            for (const glm::vec2& uv : c)
            {
                m.positions.emplace_back(2.0f * uv.x - 1.0f, 1.0f - 2.0f * uv.y, 0.0f);
                m.normals.emplace_back(0, 0, 1);
                m.tangents.emplace_back(1, 0, 0, 1);
                m.uvs.push_back(2.0f * uv);
                m.uvs1.push_back(uv);
            }
            m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        }
    // The normal map: one texel, (0.3, -0.25, 0.92) encoded.
    const glm::vec3 n = glm::normalize(glm::vec3(0.3f, -0.25f, 0.92f));
    std::vector<uint8_t> texel(4, 255);
    for (int c = 0; c < 3; ++c)
        texel[size_t(c)] =
            normal_texel ? normal_texel[c] : uint8_t(std::lround((n[c] * 0.5f + 0.5f) * 255.0f));
    normal = glm::normalize(glm::vec3(texel[0], texel[1], texel[2]) / 255.0f * 2.0f - 1.0f);
    a.images.push_back({"normal.png", "image/png", hemi::io::encode_png({1, 1, texel})});
    hemi::io::Material mat;
    albedo = glm::vec3(0.8f, 0.6f, 0.4f);
    mat.base_color_factor = glm::vec4(albedo, 1.0f);
    mat.normal.image = 0;
    a.materials.push_back(mat);
    a.primitives.push_back({0, uint32_t(m.indices.size()), 0});

    hemi::bake::LightmapUvReport report;
    const hemi::bake::LightmapAtlas atlas = hemi::bake::rasterize_lightmap(m, kAtlas, kAtlas, report);
    hemi::bake::LightmapLights lights;
    lights.uniform = glm::vec3(0.3f, 0.35f, 0.4f);
    lights.sun = true;
    lights.sun_direction = glm::normalize(glm::vec3(0.5f, -0.3f, 0.7f));
    lights.sun_irradiance = glm::vec3(2.0f, 1.8f, 1.5f);
    // A point light close to the floor: the lighting varies across the atlas (so the UV set matters).
    hemi::io::PunctualLight bulb;
    bulb.position = glm::vec3(-0.5f, 0.3f, 0.35f);
    bulb.intensity = 0.6f;
    lights.punctual.push_back(bulb);
    if (furnace)
        lights = hemi::bake::LightmapLights{}; // uniform radiance 1
    hemi::bake::LightmapBakeOptions o;
    o.rays = furnace ? 1024 : 64;
    const hemi::bake::LightmapSh sh = hemi::bake::bake_lightmap_sh(m, atlas, lights, o);
    a.width = a.height = kAtlas;
    a.covered_texels = uint32_t(atlas.texels.size());
    for (const std::string& name : outputs)
        a.outputs.push_back({name, uint32_t(hemi::bake::lightmap_output_size(name)),
                             hemi::bake::lightmap_maps(name, atlas, sh)});
    return a;
}

std::vector<float> floats_of_half(const std::vector<std::byte>& bytes)
{
    std::vector<float> out(bytes.size() / 2);
    for (size_t i = 0; i < out.size(); ++i)
    {
        uint16_t h;
        std::memcpy(&h, bytes.data() + 2 * i, 2);
        out[i] = glm::unpackHalf1x16(h);
    }
    return out;
}

} // namespace

TEST_F(LightmapMaterial, EveryBasisMatchesCpuEvaluationBesideAPrtObjectInTheCallersPass)
{
    auto& dev = hemi::test::device();
    const std::vector<std::string> techniques = {"sh9", "hl2", "h4", "h6", "sal4", "plain"};
    glm::vec3 albedo, normal;
    const hemi::io::LightmapAsset asset = floor_asset(techniques, albedo, normal);

    // A PRT sphere beside the floor, drawn in the same pass.
    hemi::io::PrtAsset sphere;
    sphere.mesh = hemi::io::make_uv_sphere(0.3f, 24, 12);
    sphere.order = 3;
    sphere.transfer_kind = 0;
    sphere.materials.emplace_back();
    sphere.primitives.push_back({0, uint32_t(sphere.mesh.indices.size()), 0});
    {
        hemi::bake::PrtBakeOptions o;
        o.kind = hemi::bake::TransferKind::Unshadowed;
        o.order = 3;
        sphere.techniques.push_back(
            {"gs",
             9,
             hemi::bake::fold_technique(hemi::bake::bake_prt_transfer(sphere.mesh, o), sphere.mesh, "gs"),
             {}});
    }

    const hemi::test::EnginePass engine(W, H, {VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT});
    hemi::render::RenderTargetDesc target;
    target.render_pass = engine.render_pass;
    target.color_attachments = 2;
    target.aux_output = true;
    hemi::render::MaterialSystem system(dev, target);
    hemi::gpu::UploadBatch upload(dev);
    hemi::render::LightmapModel floor(system, asset, techniques, upload);
    hemi::render::PrtModel prt(system, sphere, {"gs", false, 1}, upload);
    hemi::render::FrameSet frame(system);
    hemi::render::FrameData f;
    f.view_projection = hemi::render::look_at_projection(glm::vec3(0, -2.2f, 2.2f), glm::vec3(0, 0.1f, 0),
                                                         50.0f, float(W) / H);
    const glm::mat4 identity(1.0f),
        sphere_model = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0.4f, 0.3f));
    std::vector<glm::vec3> uniform(9, glm::vec3(0.0f));
    uniform[0] = glm::vec3(2.0f * std::sqrt(float(M_PI)));
    const hemi::render::PrtInstance instance{sphere_model, uniform, 0.0f};

    for (const std::string& technique : techniques)
    {
        const float clear[4] = {0, 0, 0, 0};
        hemi::gpu::one_shot(dev,
                            [&](VkCommandBuffer cmd)
                            {
                                upload.record(cmd);
                                prt.record_transfer(cmd, std::span(&instance, 1));
                                frame.record_update(cmd, f);
                                engine.begin(cmd, clear);
                                floor.draw(cmd, frame.set(), technique, identity);
                                prt.draw(cmd, frame.set(), 0, sphere_model);
                                vkCmdEndRenderPass(cmd);
                            });
        const std::vector<float> color = floats_of_half(
            hemi::gpu::read_image(dev, engine.colors[0], VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL));
        std::vector<float> aux(size_t(W) * H * 4);
        {
            const std::vector<std::byte> b =
                hemi::gpu::read_image(dev, engine.colors[1], VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
            std::memcpy(aux.data(), b.data(), b.size());
        }
        const hemi::io::LightmapOutput& out = asset.output(technique);
        const hemi::math::BasisDesc& basis = hemi::render::lightmap_basis(technique);
        float b[16];
        basis.eval(normal, b);
        auto coefficient = [&](uint32_t k, int x, int y)
        {
            x = std::clamp(x, 0, int(kAtlas) - 1);
            y = std::clamp(y, 0, int(kAtlas) - 1);
            const glm::vec3 t = out.maps.at(k, x, y);
            return glm::vec3(glm::unpackHalf1x16(glm::packHalf1x16(t[0])),
                             glm::unpackHalf1x16(glm::packHalf1x16(t[1])),
                             glm::unpackHalf1x16(glm::packHalf1x16(t[2])));
        };
        int compared = 0, failures = 0, sphere_pixels = 0;
        for (uint32_t py = 0; py < H; py += 3)
            for (uint32_t px = 0; px < W; px += 3)
            {
                const float* a = &aux[(size_t(py) * W + px) * 4];
                if (a[3] != 1.0f)
                    continue;
                const glm::vec2 uv0(a[0], a[1]);
                // Both draws are draw id 1: the sphere's pixels are told apart by where it projects (they are
                // the PRT material's, compared elsewhere), with a margin.
                const glm::vec4 centre = f.view_projection * sphere_model * glm::vec4(0, 0, 0, 1);
                const glm::vec2 sp((centre.x / centre.w * 0.5f + 0.5f) * W,
                                   (centre.y / centre.w * 0.5f + 0.5f) * H);
                if (glm::length(glm::vec2(px, py) - sp) < 28.0f)
                {
                    ++sphere_pixels;
                    continue;
                }
                const glm::vec2 uv1 = uv0 * 0.5f;
                const float fx = uv1.x * kAtlas - 0.5f, fy = uv1.y * kAtlas - 0.5f;
                const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
                const float ax = fx - float(x0), ay = fy - float(y0);
                glm::vec3 e(0.0f);
                for (uint32_t k = 0; k < out.k; ++k)
                {
                    const glm::vec3 c = glm::mix(
                        glm::mix(coefficient(k, x0, y0), coefficient(k, x0 + 1, y0), ax),
                        glm::mix(coefficient(k, x0, y0 + 1), coefficient(k, x0 + 1, y0 + 1), ax), ay);
                    e += c * b[k];
                }
                const glm::vec3 want = albedo * e / float(M_PI);
                ++compared;
                for (int ch = 0; ch < 3; ++ch)
                {
                    const float got = color[(size_t(py) * W + px) * 4 + size_t(ch)];
                    if (std::abs(got - want[ch]) > 0.005f * std::abs(want[ch]) + 2e-3f && failures++ < 5)
                        ADD_FAILURE() << technique << " pixel " << px << "," << py << " uv1 " << uv1.x << ","
                                      << uv1.y << " ch " << ch << ": GPU " << got << ", CPU " << want[ch];
                }
            }
        EXPECT_GT(compared, 200) << technique;
        EXPECT_GT(sphere_pixels, 20) << technique << ": the PRT object is drawn in the same pass";
    }
}

// "Done when" line 3: a rendered view across a chart seam shows no discontinuity beyond the noise. A floor
// in two charts (its halves x < 0 and x > 0, far apart in the atlas) under a point light above the seam,
// against the same floor in one chart at the same texel density: in a top-down view the two agree at every
// pixel within 1.5 texels of the seam to 2% (the bakes' noise; without dilation the seam shows a dark line
// 40% deep).
TEST_F(LightmapMaterial, ChartSeamShowsNoDiscontinuity)
{
    auto& dev = hemi::test::device();
    auto floor = [&](bool split)
    {
        hemi::io::LightmapAsset a;
        hemi::io::Mesh& m = a.mesh;
        // Texels 1/12 unit wide in a 32 x 32 atlas: two charts of 12 x 24 texels, or one of 24 x 24.
        auto quad = [&](float x0, float width, float u0)
        {
            const uint32_t base = uint32_t(m.positions.size());
            const glm::vec2 corners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            for (const glm::vec2& c : corners)
            {
                const glm::vec3 p(x0 + width * c.x, -1.0f + 2.0f * c.y, 0.0f);
                m.positions.push_back(p);
                m.normals.emplace_back(0, 0, 1);
                m.tangents.emplace_back(1, 0, 0, 1);
                m.uvs.emplace_back(p.x, -p.y);
                m.uvs1.emplace_back((u0 + 12.0f * width * c.x) / 32.0f,
                                    (4.0f + 24.0f * (1.0f - c.y)) / 32.0f);
            }
            m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        };
        if (split)
        {
            quad(-1.0f, 1.0f, 2.0f);
            quad(0.0f, 1.0f, 18.0f);
        }
        else
            quad(-1.0f, 2.0f, 2.0f);
        a.materials.emplace_back();
        a.primitives.push_back({0, uint32_t(m.indices.size()), 0});
        hemi::bake::LightmapUvReport report;
        const hemi::bake::LightmapAtlas atlas = hemi::bake::rasterize_lightmap(m, 32, 32, report);
        EXPECT_TRUE(report.ok());
        hemi::bake::LightmapLights lights;
        lights.uniform = glm::vec3(0.2f);
        hemi::io::PunctualLight bulb;
        bulb.position = glm::vec3(0.0f, 0.2f, 0.5f);
        bulb.intensity = 0.5f;
        lights.punctual.push_back(bulb);
        hemi::bake::LightmapBakeOptions o;
        o.rays = 1024;
        const hemi::bake::LightmapSh sh = hemi::bake::bake_lightmap_sh(m, atlas, lights, o);
        a.width = a.height = 32;
        a.covered_texels = uint32_t(atlas.texels.size());
        a.outputs.push_back({"h4", 4, hemi::bake::lightmap_maps("h4", atlas, sh)});
        return a;
    };
    const uint32_t size = 144;
    auto render = [&](const hemi::io::LightmapAsset& a)
    {
        hemi::render::LightmapView view(dev, a, {"h4"}, size, size);
        hemi::render::LightmapFrame frame;
        frame.technique = "h4";
        frame.model = glm::mat4(1.0f);
        frame.white = true;
        frame.camera.eye = glm::vec3(0.0f, 0.0f, 3.2f);
        frame.camera.target = glm::vec3(0.0f);
        return view.render(frame);
    };
    const hemi::io::LightmapAsset split = floor(true), whole = floor(false);
    const hemi::io::ImageRgba a = render(split), b = render(whole);
    // The seam's column: where x = 0 projects (the view is symmetric about it); a texel is about 5 pixels.
    const uint32_t seam = size / 2;
    int compared = 0;
    for (uint32_t y = 20; y + 20 < size; ++y)
        for (uint32_t x = seam - 8; x < seam + 8; ++x)
        {
            if (a.at(x, y)[3] != 1.0f || b.at(x, y)[3] != 1.0f)
                continue;
            ++compared;
            ASSERT_NEAR(a.at(x, y)[0], b.at(x, y)[0], 0.02f * b.at(x, y)[0] + 1e-3f)
                << "pixel (" << x << ", " << y << ")";
        }
    EXPECT_GT(compared, 1000);
}

// Green 2007's two materials on lightmaps, from the baker's "rnm" output: radiosity normal mapping (Listing
// 1, the normal-map normal's squared, normalised weights of Valve's directions) and the SSBump material
// (Listing 2, the weights stored in the normal-map slot) each equal a CPU evaluation at sampled pixels; with
// no relief (an SSBump texel of 1/3 each) the SSBump material equals Listing 1 with a flat normal map; under
// uniform radiance 1 an open flat floor renders its albedo with either material (issue 11's white furnace:
// the rnm colours are normalised to pi each over a texel's hemisphere).
TEST_F(LightmapMaterial, RadiosityNormalMappingAndSsbumpMatchTheirListings)
{
    auto& dev = hemi::test::device();
    const uint8_t ssbump_texel[3] = {150, 60, 20};
    const uint8_t flat_ssbump[3] = {85, 85, 85};
    const uint8_t flat_normal[3] = {128, 128, 255};
    glm::vec3 albedo, normal;
    const hemi::io::LightmapAsset tilted = floor_asset({"rnm"}, albedo, normal);
    const glm::vec3 tilted_normal = normal;
    const hemi::io::LightmapAsset bumped = floor_asset({"rnm"}, albedo, normal, ssbump_texel);
    const hemi::io::LightmapAsset flat_s = floor_asset({"rnm"}, albedo, normal, flat_ssbump);
    const hemi::io::LightmapAsset flat_n = floor_asset({"rnm"}, albedo, normal, flat_normal);
    const uint32_t size = 96;
    auto render = [&](const hemi::io::LightmapAsset& a, const std::string& technique, bool white = false)
    {
        hemi::render::LightmapView view(dev, a, {technique}, size, size);
        hemi::render::LightmapFrame frame;
        frame.technique = technique;
        frame.model = glm::mat4(1.0f);
        frame.white = white;
        frame.camera.eye = glm::vec3(0.0f, -0.3f, 2.6f);
        frame.camera.target = glm::vec3(0.0f);
        return view.render(frame);
    };
    // Where each pixel lands on the floor: the view's own projection, inverted on the plane z = 0.
    const glm::mat4 vp = hemi::render::camera_matrix({glm::vec3(0.0f, -0.3f, 2.6f), glm::vec3(0.0f), 35.0f},
                                                     tilted.mesh, glm::mat4(1.0f), 1.0f);
    const glm::mat4 inv = glm::inverse(vp);
    auto floor_point = [&](uint32_t px, uint32_t py) { return point_on_floor(inv, size, px, py); };
    const hemi::io::LightmapOutput& rnm = tilted.output("rnm");
    auto lightmap = [&](const glm::vec2& uv1)
    {
        std::array<glm::vec3, 3> c{};
        const float fx = uv1.x * kAtlas - 0.5f, fy = uv1.y * kAtlas - 0.5f;
        const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
        const float ax = fx - float(x0), ay = fy - float(y0);
        for (uint32_t k = 0; k < 3; ++k)
        {
            auto t = [&](int x, int y)
            {
                x = std::clamp(x, 0, int(kAtlas) - 1), y = std::clamp(y, 0, int(kAtlas) - 1);
                const glm::vec3 v = rnm.maps.at(uint32_t(k), x, y);
                return glm::vec3(glm::unpackHalf1x16(glm::packHalf1x16(v[0])),
                                 glm::unpackHalf1x16(glm::packHalf1x16(v[1])),
                                 glm::unpackHalf1x16(glm::packHalf1x16(v[2])));
            };
            c[k] = glm::mix(glm::mix(t(x0, y0), t(x0 + 1, y0), ax),
                            glm::mix(t(x0, y0 + 1), t(x0 + 1, y0 + 1), ax), ay);
        }
        return c;
    };
    // Valve's bumpBasis, typed from Source.
    const glm::vec3 basis[3] = {{0.81649658f, 0.0f, 0.57735027f},
                                {-0.40824829f, 0.70710678f, 0.57735027f},
                                {-0.40824829f, -0.70710678f, 0.57735027f}};
    const hemi::io::ImageRgba listing1 = render(tilted, "rnm"), listing2 = render(bumped, "ssbump");
    int compared = 0;
    for (uint32_t py = 10; py < size - 10; py += 3)
        for (uint32_t px = 10; px < size - 10; px += 3)
        {
            if (listing1.at(px, py)[3] != 1.0f || listing2.at(px, py)[3] != 1.0f)
                continue;
            const glm::vec3 p = floor_point(px, py);
            if (std::abs(p.x) > 0.95f || std::abs(p.y) > 0.95f)
                continue;
            const glm::vec2 uv1((p.x + 1.0f) * 0.5f, (1.0f - p.y) * 0.5f);
            const std::array<glm::vec3, 3> c = lightmap(uv1);
            glm::vec3 dp;
            for (int i = 0; i < 3; ++i)
                dp[i] = std::pow(std::clamp(glm::dot(tilted_normal, basis[i]), 0.0f, 1.0f), 2.0f);
            const glm::vec3 e1 = (dp.x * c[0] + dp.y * c[1] + dp.z * c[2]) / (dp.x + dp.y + dp.z);
            const glm::vec3 e2 = ssbump_texel[0] / 255.0f * c[0] + ssbump_texel[1] / 255.0f * c[1] +
                                 ssbump_texel[2] / 255.0f * c[2];
            for (int ch = 0; ch < 3; ++ch)
            {
                const float w1 = albedo[ch] * e1[ch] / float(M_PI), w2 = albedo[ch] * e2[ch] / float(M_PI);
                ASSERT_NEAR(listing1.at(px, py)[ch], w1, 0.01f * w1 + 2e-3f)
                    << "rnm pixel " << px << "," << py;
                ASSERT_NEAR(listing2.at(px, py)[ch], w2, 0.01f * w2 + 2e-3f)
                    << "ssbump pixel " << px << "," << py;
            }
            ++compared;
        }
    EXPECT_GT(compared, 200);

    // No relief: the SSBump material equals Listing 1 with a flat normal map.
    const hemi::io::ImageRgba s = render(flat_s, "ssbump"), n = render(flat_n, "rnm");
    for (uint32_t py = 0; py < size; ++py)
        for (uint32_t px = 0; px < size; ++px)
        {
            if (s.at(px, py)[3] != 1.0f)
                continue;
            for (int ch = 0; ch < 3; ++ch)
                ASSERT_NEAR(s.at(px, py)[ch], n.at(px, py)[ch], 0.005f * n.at(px, py)[ch] + 1e-4f)
                    << px << "," << py;
        }

    // The furnace of an open flat floor under uniform radiance 1: it renders its albedo with either material.
    const hemi::io::LightmapAsset furnace = floor_asset({"rnm"}, albedo, normal, flat_ssbump, true);
    const hemi::io::ImageRgba f = render(furnace, "ssbump");
    const hemi::io::LightmapAsset furnace_n = floor_asset({"rnm"}, albedo, normal, flat_normal, true);
    const hemi::io::ImageRgba fn = render(furnace_n, "rnm");
    int covered = 0;
    for (uint32_t py = 0; py < size; ++py)
        for (uint32_t px = 0; px < size; ++px)
            if (f.at(px, py)[3] == 1.0f)
            {
                ++covered;
                for (int ch = 0; ch < 3; ++ch)
                {
                    ASSERT_NEAR(f.at(px, py)[ch], albedo[ch], 0.01f * albedo[ch])
                        << "ssbump " << px << "," << py;
                    ASSERT_NEAR(fn.at(px, py)[ch], albedo[ch], 0.01f * albedo[ch])
                        << "rnm " << px << "," << py;
                }
            }
    EXPECT_GT(covered, 1000);
}

// The probes' light for a dynamic object (render::probe_lighting): a level placed by glTF's rotation and
// moved by (3, -1, 2) hands an object at a world position the probes' interpolation at that position in the
// level's space, rotated into the world: the world SH9 evaluated at R n equals the level's SH9 at n for any
// n (SH9 typed here), at a probe's position and between two probes. An asset without probes is refused.
TEST(LightmapProbes, ProbeLightingRotatesTheLevelsProbesIntoTheWorld)
{
    hemi::io::LightmapAsset asset;
    asset.probes.count = glm::uvec3(2, 1, 1);
    asset.probes.lo = glm::vec3(0.0f, 1.0f, 0.0f);
    asset.probes.hi = glm::vec3(4.0f, 1.0f, 0.0f);
    for (int p = 0; p < 2; ++p)
    {
        std::array<glm::vec3, 9> e{};
        for (int j = 0; j < 9; ++j)
            e[size_t(j)] =
                glm::vec3(std::sin(1.3f * float(j + 1) + float(p)), 0.5f * float(j) - float(p), 1.0f);
        asset.probes.irradiance.push_back(e);
        asset.probes.valid.push_back(1);
    }
    const glm::mat4 model =
        glm::translate(glm::mat4(1.0f), glm::vec3(3.0f, -1.0f, 2.0f)) * hemi::render::gltf_to_world();
    const glm::mat3 r(model);
    for (const float x : {0.0f, 1.0f, 4.0f})
    {
        // Scene point (x, 1, 0): world (x + 3, -1 + 0, 2 + 1) under (x, y, z) -> (x, -z, y).
        std::array<glm::vec3, 9> world;
        ASSERT_TRUE(hemi::render::probe_lighting(asset, glm::vec3(x + 3.0f, -1.0f, 3.0f), model, world));
        const float t = x / 4.0f;
        for (const glm::dvec3 n :
             {glm::dvec3(0, 0, 1), glm::dvec3(0.6, 0.0, -0.8), glm::dvec3(0.48, -0.6, 0.64)})
        {
            const std::array<double, 9> ys = sh9(n), yw = sh9(glm::dvec3(r * glm::vec3(n)));
            glm::dvec3 scene(0.0), turned(0.0);
            for (int j = 0; j < 9; ++j)
            {
                const glm::vec3 c = (1.0f - t) * asset.probes.irradiance[0][size_t(j)] +
                                    t * asset.probes.irradiance[1][size_t(j)];
                scene += glm::dvec3(c) * ys[size_t(j)];
                turned += glm::dvec3(world[size_t(j)]) * yw[size_t(j)];
            }
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(turned[ch], scene[ch], 1e-5) << "x " << x << " channel " << ch;
        }
    }
    std::array<glm::vec3, 9> none;
    none.fill(glm::vec3(1.0f));
    EXPECT_FALSE(hemi::render::probe_lighting(hemi::io::LightmapAsset{}, glm::vec3(0.0f), model, none));
    EXPECT_EQ(none[0], glm::vec3(0.0f)) << "refused lighting is zero, not what the array held";
}

// A dynamic object beside the lightmapped level: LightmapView draws a sphere lit by the asset's probes in the
// same render pass (the material system's SH9 probe material, world frame), under the validation layer.
// Every pixel well inside the sphere's silhouette shows E(n) / pi of the probes' SH9 irradiance at the
// sphere's surface normal there (lighting-only view; SH9 and the ray-sphere intersection typed here), to 1%
// (the sphere's per-vertex normals); between two probes it is their average. A frame with spheres but an
// asset without probes is refused.
TEST_F(LightmapMaterial, SpheresLitByTheAssetsProbesBesideTheLevel)
{
    auto& dev = hemi::test::device();
    glm::vec3 albedo, normal;
    hemi::io::LightmapAsset asset = floor_asset({"sh9"}, albedo, normal);
    asset.probes.count = glm::uvec3(2, 1, 1);
    asset.probes.lo = glm::vec3(-0.5f, 0.0f, 0.5f);
    asset.probes.hi = glm::vec3(0.5f, 0.0f, 0.5f);
    // The two probes: the SH9 irradiance of a light from (0.48, -0.6, 0.64) and of one from -x, plus a little
    // sky.
    for (const glm::dvec3 d : {glm::dvec3(0.48, -0.6, 0.64), glm::dvec3(-1.0, 0.0, 0.0)})
    {
        const double a[9] = {M_PI,     2 * M_PI / 3, 2 * M_PI / 3, 2 * M_PI / 3, M_PI / 4,
                             M_PI / 4, M_PI / 4,     M_PI / 4,     M_PI / 4};
        const std::array<double, 9> y = sh9(d);
        std::array<glm::vec3, 9> e{};
        for (int j = 0; j < 9; ++j)
            e[size_t(j)] = glm::vec3(float(a[j] * y[size_t(j)]) * glm::vec3(2.0f, 1.5f, 1.0f));
        e[0] += glm::vec3(0.5f); // + a constant 0.5 * 0.282095 E
        asset.probes.irradiance.push_back(e);
        asset.probes.valid.push_back(1);
    }
    const uint32_t size = 96;
    hemi::render::LightmapView view(dev, asset, {"sh9"}, size, size);
    hemi::render::LightmapFrame frame;
    frame.technique = "sh9";
    frame.model = glm::mat4(1.0f);
    frame.white = true;
    frame.camera.eye = glm::vec3(0.0f, -2.4f, 1.2f);
    frame.camera.target = glm::vec3(0.0f, 0.0f, 0.3f);
    const glm::vec4 sphere(0.0f, 0.0f, 0.5f, 0.35f); // halfway between the probes
    frame.spheres = {sphere};
    const hemi::io::ImageRgba image = view.render(frame);
    const glm::mat4 inv =
        glm::inverse(hemi::render::camera_matrix(frame.camera, asset.mesh, frame.model, 1.0f));
    int compared = 0;
    for (uint32_t py = 0; py < size; ++py)
        for (uint32_t px = 0; px < size; ++px)
        {
            const glm::vec2 ndc((px + 0.5f) / size * 2.0f - 1.0f, (py + 0.5f) / size * 2.0f - 1.0f);
            const glm::vec4 a = inv * glm::vec4(ndc, 0.0f, 1.0f), b = inv * glm::vec4(ndc, 1.0f, 1.0f);
            const glm::dvec3 o = glm::dvec3(glm::vec3(a) / a.w),
                             d = glm::normalize(glm::dvec3(glm::vec3(b) / b.w) - o);
            const glm::dvec3 oc = o - glm::dvec3(glm::vec3(sphere));
            const double bq = glm::dot(oc, d), cq = glm::dot(oc, oc) - double(sphere.w) * sphere.w;
            const double disc = bq * bq - cq;
            if (disc < 0.05 * double(sphere.w) * sphere.w) // near the silhouette or off the sphere
                continue;
            const glm::dvec3 n =
                glm::normalize(o + d * (-bq - std::sqrt(disc)) - glm::dvec3(glm::vec3(sphere)));
            const std::array<double, 9> y = sh9(n);
            for (int ch = 0; ch < 3; ++ch)
            {
                double e = 0.0;
                for (int j = 0; j < 9; ++j)
                    e += 0.5 *
                         (asset.probes.irradiance[0][size_t(j)][ch] +
                          asset.probes.irradiance[1][size_t(j)][ch]) *
                         y[size_t(j)];
                const double expected = e / M_PI;
                ASSERT_NEAR(image.at(px, py)[ch], expected, 0.01 * std::abs(expected) + 2e-3)
                    << "pixel (" << px << ", " << py << ") channel " << ch;
            }
            ++compared;
        }
    EXPECT_GT(compared, 400);
    hemi::io::LightmapAsset no_probes = floor_asset({"sh9"}, albedo, normal);
    hemi::render::LightmapView plain_view(dev, no_probes, {"sh9"}, 16, 16);
    EXPECT_THROW(plain_view.render(frame), std::invalid_argument);
}

// Dynamic lights on Green's two materials (issue 11): a directional and a point light with a specular term,
// added to the lightmap. The difference between the frame with the lights and the same frame without them
// equals, at sampled pixels, what this test computes from the paper's forms: Listing 1 lights the normal-map
// normal (albedo E max(0, n.l) / pi), the SSBump material projects each light onto Valve's three directions
// and dots them with the texel (albedo E sqrt(3) sum_i w_i saturate(B_i.l) / pi), each with normalised
// Blinn-Phong, (m + 8) / (8 pi) (n.h)^m (n.l) E, at its normal (the SSBump one reconstructed as
// normalize(sum_i w_i B_i)); 1% + 1e-3. A flat SSBump texel under a light straight above gets the light's
// full E (the sqrt 3 normalisation). Validation layer on (the fixture).
TEST_F(LightmapMaterial, DynamicLightsOnRadiosityNormalMappingAndSsbump)
{
    auto& dev = hemi::test::device();
    const uint8_t ssbump_texel[3] = {150, 60, 20};
    const uint8_t flat_ssbump[3] = {85, 85, 85};
    glm::vec3 albedo, normal;
    const hemi::io::LightmapAsset tilted = floor_asset({"rnm"}, albedo, normal);
    const glm::vec3 n_map = normal;
    const hemi::io::LightmapAsset bumped = floor_asset({"rnm"}, albedo, normal, ssbump_texel);
    const hemi::io::LightmapAsset flat = floor_asset({"rnm"}, albedo, normal, flat_ssbump);
    const uint32_t size = 96;
    const glm::vec3 eye(0.0f, -0.3f, 2.6f);
    std::vector<hemi::render::DynamicLight> lights(2);
    lights[0].position = glm::vec3(0.5f, -0.4f, 0.8f); // towards the directional light
    lights[0].irradiance = glm::vec3(1.5f, 1.2f, 1.0f);
    lights[1].point = true;
    lights[1].position = glm::vec3(0.4f, 0.3f, 0.6f);
    lights[1].irradiance = glm::vec3(0.3f, 0.35f, 0.4f);
    const float exponent = 24.0f, strength = 0.4f;
    auto render = [&](const hemi::io::LightmapAsset& a, const std::string& technique, bool lit, float spec,
                      std::vector<hemi::render::DynamicLight> with)
    {
        hemi::render::LightmapView view(dev, a, {technique}, size, size);
        hemi::render::LightmapFrame frame;
        frame.technique = technique;
        frame.model = glm::mat4(1.0f);
        frame.camera.eye = eye;
        frame.camera.target = glm::vec3(0.0f);
        if (lit)
        {
            frame.lights = with.empty() ? lights : with;
            frame.specular_exponent = exponent;
            frame.specular_strength = spec;
        }
        return view.render(frame);
    };
    const glm::mat4 inv = glm::inverse(
        hemi::render::camera_matrix({eye, glm::vec3(0.0f), 35.0f}, tilted.mesh, glm::mat4(1.0f), 1.0f));
    auto floor_point = [&](uint32_t px, uint32_t py) { return point_on_floor(inv, size, px, py); };
    const glm::dvec3 basis[3] = {{0.81649658, 0.0, 0.57735027},
                                 {-0.40824829, 0.70710678, 0.57735027},
                                 {-0.40824829, -0.70710678, 0.57735027}};
    const glm::dvec3 w(ssbump_texel[0] / 255.0, ssbump_texel[1] / 255.0, ssbump_texel[2] / 255.0);
    const glm::dvec3 reconstructed = glm::normalize(w.x * basis[0] + w.y * basis[1] + w.z * basis[2]);
    for (const std::string technique : {"rnm", "ssbump"})
    {
        const hemi::io::LightmapAsset& asset = technique == "rnm" ? tilted : bumped;
        const hemi::io::ImageRgba on = render(asset, technique, true, strength, {});
        const hemi::io::ImageRgba off = render(asset, technique, false, 0.0f, {});
        const glm::dvec3 n = technique == "rnm" ? glm::dvec3(n_map) : reconstructed;
        int compared = 0;
        for (uint32_t py = 8; py < size - 8; py += 4)
            for (uint32_t px = 8; px < size - 8; px += 4)
            {
                if (on.at(px, py)[3] != 1.0f)
                    continue;
                const glm::dvec3 p(floor_point(px, py));
                if (std::abs(p.x) > 0.95 || std::abs(p.y) > 0.95)
                    continue;
                const glm::dvec3 v = glm::normalize(glm::dvec3(eye) - p);
                glm::dvec3 diffuse(0.0), specular(0.0);
                for (const hemi::render::DynamicLight& l : lights)
                {
                    glm::dvec3 to = glm::dvec3(l.position) - (l.point ? p : glm::dvec3(0.0));
                    const double d2 = l.point ? glm::dot(to, to) : 1.0;
                    to = glm::normalize(to);
                    const glm::dvec3 e = glm::dvec3(l.irradiance) / d2;
                    double f = 0.0;
                    if (technique == "rnm")
                        f = std::max(0.0, glm::dot(n, to));
                    else
                        for (int i = 0; i < 3; ++i)
                            f += std::sqrt(3.0) * w[i] * std::clamp(glm::dot(basis[i], to), 0.0, 1.0);
                    diffuse += e * f;
                    const glm::dvec3 h = glm::normalize(to + v);
                    specular += e * std::max(0.0, glm::dot(n, to)) *
                                std::pow(std::max(0.0, glm::dot(n, h)), double(exponent));
                }
                specular *= strength * (exponent + 8.0) / (8.0 * M_PI);
                for (int ch = 0; ch < 3; ++ch)
                {
                    const double expected = albedo[ch] * diffuse[ch] / M_PI + specular[ch];
                    ASSERT_NEAR(on.at(px, py)[ch] - off.at(px, py)[ch], expected, 0.01 * expected + 1e-3)
                        << technique << " pixel (" << px << ", " << py << ") channel " << ch;
                }
                ++compared;
            }
        EXPECT_GT(compared, 200) << technique;
    }
    // A flat SSBump texel under one light straight above, no specular: the light's full E times albedo / pi.
    std::vector<hemi::render::DynamicLight> overhead(1);
    overhead[0].irradiance = glm::vec3(2.0f);
    const hemi::io::ImageRgba a = render(flat, "ssbump", true, 0.0f, overhead),
                              b = render(flat, "ssbump", false, 0.0f, {});
    for (uint32_t i = 0; i < size * size; i += 7)
        if (a.pixels[i * 4 + 3] == 1.0f)
        {
            ASSERT_NEAR(a.pixels[i * 4] - b.pixels[i * 4],
                        albedo.x * 2.0f * (85.0f / 255.0f * 3.0f) / float(M_PI), 2e-3f);
        }
    // Too many lights are refused.
    EXPECT_THROW(
        render(flat, "ssbump", true, 0.0f, std::vector<hemi::render::DynamicLight>(HEMI_MAX_LIGHTS + 1)),
        std::invalid_argument);
}

// Green's second baseline, radiosity normal mapping with a plain ambient-occlusion channel (rnm_ao): the
// material's glTF occlusion texture, 1 + strength (r - 1), multiplies the diffuse light, the lightmap's and a
// dynamic light's: with a texel r = 0.4 at strength 0.5 every pixel is 0.7 of Listing 1's (1%); without an
// occlusion texture rnm_ao is Listing 1. Validation layer on.
TEST_F(LightmapMaterial, AmbientOcclusionBaselineScalesListingOne)
{
    auto& dev = hemi::test::device();
    glm::vec3 albedo, normal;
    hemi::io::LightmapAsset plain = floor_asset({"rnm"}, albedo, normal);
    hemi::io::LightmapAsset occluded = plain;
    occluded.images.push_back({"ao.png", "image/png", hemi::io::encode_png({1, 1, {102, 0, 0, 255}})});
    occluded.materials[0].occlusion.image = 1;
    occluded.materials[0].occlusion_strength = 0.5f;
    const float factor = 1.0f + 0.5f * (102.0f / 255.0f - 1.0f);
    const uint32_t size = 64;
    auto render = [&](const hemi::io::LightmapAsset& a, const std::string& technique)
    {
        hemi::render::LightmapView view(dev, a, {technique}, size, size);
        hemi::render::LightmapFrame frame;
        frame.technique = technique;
        frame.model = glm::mat4(1.0f);
        frame.camera.eye = glm::vec3(0.0f, -0.3f, 2.6f);
        frame.camera.target = glm::vec3(0.0f);
        hemi::render::DynamicLight light;
        light.position = glm::vec3(-0.4f, 0.2f, 0.9f);
        light.irradiance = glm::vec3(1.0f, 0.8f, 0.6f);
        frame.lights = {light};
        return view.render(frame);
    };
    const hemi::io::ImageRgba listing1 = render(occluded, "rnm"), ao = render(occluded, "rnm_ao");
    const hemi::io::ImageRgba listing1_plain = render(plain, "rnm"), ao_plain = render(plain, "rnm_ao");
    int covered = 0;
    for (size_t i = 0; i < listing1.pixels.size(); i += 4)
    {
        if (listing1.pixels[i + 3] != 1.0f)
            continue;
        ++covered;
        for (int c = 0; c < 3; ++c)
        {
            ASSERT_NEAR(ao.pixels[i + c], factor * listing1.pixels[i + c],
                        0.01f * listing1.pixels[i + c] + 1e-4f);
            ASSERT_NEAR(ao_plain.pixels[i + c], listing1_plain.pixels[i + c], 1e-4f);
        }
    }
    EXPECT_GT(covered, 500);
}
