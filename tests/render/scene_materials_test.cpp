// A glTF scene as exporters write it, end to end: several primitives with their own materials (a PNG base
// colour beside the file, a JPEG normal map inside the .glb's buffer, a PNG as a data URI, colour and
// emissive factors, a double-sided open panel seen from behind, a plain material with no texture), baked by
// hemi-bake's path, the asset moved to another folder with the scene and its textures deleted, and rendered
// from there. Every sampled pixel equals a CPU evaluation of its own primitive's material.
//
// The CPU side is independent of the bake and of the renderer: unshadowed gold-standard transfer of order-3
// lighting is exact (SH9 projected on the SH9 basis is the identity), so a pixel is
//     albedo * E(n_world) / pi + emissive,  E(n) = sum_l A_l sum_m L_lm y_lm(n),
// with n_world the normal-map normal (the map's texel, scaled by normalTexture.scale) put through the quad's
// tangent frame as glTF defines it and through gltf_to_world(), and albedo the base colour factor times the
// sRGB-decoded texel. The aux attachment's draw id says which primitive covers the pixel.
#include "../gpu_fixture.h"
#include "../temp_dir.h"

#include <hemi/bake/prt_bake.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/sh.h>
#include <hemi/render/view/prt_view.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;
using namespace hemi;

namespace
{

class SceneMaterials : public test::GpuTest
{
};

// Blocks of 4x4 texels of one colour, so that a pixel away from block edges samples one texel exactly.
io::ImageRgba8 blocks(uint32_t w, uint32_t h, uint32_t seed)
{
    io::ImageRgba8 img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const uint32_t b = (x / 4) * 7 + (y / 4) * 13 + seed * 5;
            uint8_t* p = &img.pixels[(size_t(y) * w + x) * 4];
            p[0] = uint8_t(60 + (b * 37) % 190), p[1] = uint8_t(60 + (b * 71) % 190),
            p[2] = uint8_t(60 + (b * 113) % 190);
            p[3] = 255;
        }
    return img;
}

// A smooth tangent-space normal map (tilts of up to ~35 degrees), glTF convention.
io::ImageRgba8 smooth_normals(uint32_t w, uint32_t h)
{
    io::ImageRgba8 img{w, h, std::vector<uint8_t>(size_t(w) * h * 4)};
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
        {
            const float u = (x + 0.5f) / w, v = (y + 0.5f) / h;
            const glm::vec3 n = glm::normalize(
                glm::vec3(0.6f * std::sin(6.2831853f * u), 0.5f * std::cos(6.2831853f * v), 1.0f));
            uint8_t* p = &img.pixels[(size_t(y) * w + x) * 4];
            for (int c = 0; c < 3; ++c)
                p[c] = uint8_t(std::lround((n[c] * 0.5f + 0.5f) * 255.0f));
            p[3] = 255;
        }
    return img;
}

struct Quad
{
    glm::vec3 corner, u, v; // glTF space; UV (0,1) at corner, u along +u, v up the image (decreasing v)
};

float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

glm::vec4 texel(const io::ImageRgba8& img, uint32_t x, uint32_t y)
{
    const uint8_t* p = &img.pixels[(size_t(y) * img.width + x) * 4];
    return glm::vec4(p[0], p[1], p[2], p[3]) / 255.0f;
}

// Bilinear, repeat, texel centres at (i + 0.5) / size: the GPU's LINEAR filter on mip 0.
glm::vec4 bilinear(const io::ImageRgba8& img, glm::vec2 uv)
{
    const float x = uv.x * img.width - 0.5f, y = uv.y * img.height - 0.5f;
    const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    const float fx = x - x0, fy = y - y0;
    auto at = [&](int xi, int yi)
    {
        return texel(img, uint32_t((xi % int(img.width) + img.width) % img.width),
                     uint32_t((yi % int(img.height) + img.height) % img.height));
    };
    return glm::mix(glm::mix(at(x0, y0), at(x0 + 1, y0), fx),
                    glm::mix(at(x0, y0 + 1), at(x0 + 1, y0 + 1), fx), fy);
}

} // namespace

TEST_F(SceneMaterials, EachPrimitiveRendersWithItsOwnMaterialFromAMovedAsset)
{
    const fs::path dir = test::temp_dir("scene_materials");
    const fs::path source = dir / "source", moved = dir / "elsewhere";
    fs::remove_all(source);
    fs::remove_all(moved);
    fs::create_directories(source);
    fs::create_directories(moved);

    // Three quads facing +z (towards the auto camera once glTF +y becomes world +z), the panel's front
    // facing -z: the camera sees its back.
    const Quad quads[3] = {{{-2.3f, -0.5f, 0.0f}, {1.4f, 0, 0}, {0, 1.4f, 0}},
                           {{0.7f, -0.5f, 0.0f}, {-1.4f, 0, 0}, {0, 1.4f, 0}}, // reversed u: normal -z
                           {{1.0f, -0.5f, 0.0f}, {1.4f, 0, 0}, {0, 1.4f, 0}}};
    io::GltfScene scene;
    for (uint32_t q = 0; q < 3; ++q)
    {
        const Quad& d = quads[q];
        const uint32_t first = uint32_t(scene.mesh.positions.size());
        const glm::vec3 n = glm::normalize(glm::cross(d.u, d.v));
        const glm::vec3 p[4] = {d.corner, d.corner + d.u, d.corner + d.u + d.v, d.corner + d.v};
        const glm::vec2 uv[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
        for (int k = 0; k < 4; ++k)
        {
            scene.mesh.positions.push_back(p[k]);
            scene.mesh.normals.push_back(n);
            scene.mesh.tangents.push_back(glm::vec4(glm::normalize(d.u), 1.0f));
            scene.mesh.uvs.push_back(uv[k]);
        }
        scene.primitives.push_back({uint32_t(scene.mesh.indices.size()), 6, q});
        scene.mesh.indices.insert(scene.mesh.indices.end(),
                                  {first, first + 1, first + 2, first, first + 2, first + 3});
    }
    const io::ImageRgba8 brick = blocks(32, 32, 1), panel = blocks(16, 16, 2),
                         normals = smooth_normals(64, 64);
    scene.images.push_back({"brick base.png", "image/png", io::encode_png(brick)});
    scene.images.push_back({"brick_normal.jpg", "image/jpeg", io::encode_jpeg(normals, 95)});
    scene.images.push_back({"panel.png", "image/png", io::encode_png(panel)});
    const io::TextureSampler nearest{io::Filter::Nearest, io::Filter::Nearest, false, io::Wrap::Repeat,
                                     io::Wrap::Repeat};
    io::TextureSampler linear;
    linear.mipmaps = false;
    io::Material a;
    a.name = "brick";
    a.base_color_factor = {0.9f, 0.8f, 0.7f, 1.0f};
    a.base_color = {0, 0, nearest};
    a.normal = {1, 0, linear};
    a.normal_scale = 0.8f;
    io::Material b;
    b.name = "panel";
    b.base_color_factor = {1.0f, 0.5f, 0.25f, 1.0f};
    b.base_color = {2, 0, nearest};
    b.emissive_factor = {0.05f, 0.1f, 0.15f};
    b.double_sided = true;
    io::Material c;
    c.name = "plain";
    c.base_color_factor = {0.2f, 0.4f, 0.6f, 1.0f};
    scene.materials = {a, b, c};
    const fs::path gltf = source / "scene.glb";
    io::write_gltf(gltf, scene,
                   {io::ImageStorage::External, io::ImageStorage::BufferView, io::ImageStorage::DataUri});
    ASSERT_TRUE(fs::exists(source / "brick base.png")) << "the base colour PNG is a file beside the scene";

    bake::PrtAssetOptions options;
    options.bake.kind = bake::TransferKind::Unshadowed;
    options.bake.order = 3;
    options.techniques = {"gs"};
    bake::bake_prt_file(gltf, source / "scene.hemi", options);
    fs::rename(source / "scene.hemi", moved / "scene.hemi");
    fs::remove_all(source); // the scene and every texture file are gone
    const io::PrtAsset asset = io::read_prt_asset(moved / "scene.hemi");
    ASSERT_EQ(asset.materials.size(), 3u);
    ASSERT_EQ(asset.primitives.size(), 3u);

    const uint32_t W = 240, H = 120;
    render::PrtView view(test::device(), asset, "gs", false, W, H);
    render::PrtFrame frame;
    frame.world_lighting = render::environment_lighting("sky", 3);
    frame.camera = render::auto_camera(asset.mesh, frame.model, float(W) / float(H));
    frame.camera.eye = frame.camera.target + glm::length(frame.camera.eye - frame.camera.target) *
                                                 glm::normalize(glm::vec3(0.1f, -1.0f, 0.15f));
    const io::ImageRgba color = view.render(frame);
    const io::ImageRgba aux = view.target().read_aux();

    std::vector<glm::vec3> irradiance = frame.world_lighting;
    math::convolve_cosine(irradiance);
    const glm::mat3 to_world(render::gltf_to_world());
    const io::ImageRgba8 normal_map =
        io::decode_image(asset.images[size_t(a.normal.image)]); // what the GPU samples
    int compared[3] = {}, failures = 0;
    for (uint32_t y = 2; y + 2 < H; y += 3)
        for (uint32_t x = 2; x + 2 < W; x += 3)
        {
            const float id = aux.at(x, y)[2];
            if (aux.at(x, y)[3] != 1.0f || id < 1.0f)
                continue;
            const uint32_t p = uint32_t(std::lround(id)) - 1;
            ASSERT_LT(p, 3u);
            bool interior = true; // not at a silhouette or a block edge
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx)
                    interior = interior && aux.at(x + dx, y + dy)[2] == id;
            const glm::vec2 uv(aux.at(x, y)[0], aux.at(x, y)[1]);
            const io::Material& m = asset.materials[asset.primitives[p].material];
            glm::vec3 albedo = glm::vec3(m.base_color_factor);
            if (m.base_color.present())
            {
                const io::ImageRgba8& img = m.base_color.image == 0 ? brick : panel;
                const float fx = uv.x * img.width, fy = uv.y * img.height;
                const float ex = fx - 4.0f * std::floor(fx / 4.0f), ey = fy - 4.0f * std::floor(fy / 4.0f);
                if (ex < 0.3f || ex > 3.7f || ey < 0.3f || ey > 3.7f)
                    interior = false; // within 0.3 texels of a block edge: nearest may pick either block
                const glm::vec4 t = texel(img, uint32_t(fx) % img.width, uint32_t(fy) % img.height);
                albedo *= glm::vec3(srgb_to_linear(t.r), srgb_to_linear(t.g), srgb_to_linear(t.b));
            }
            if (!interior || uv.x < 0.02f || uv.x > 0.98f || uv.y < 0.02f || uv.y > 0.98f)
                continue;
            glm::vec3 nt(0, 0, 1);
            if (m.normal.present())
            {
                nt = glm::vec3(bilinear(normal_map, uv)) * 2.0f - 1.0f;
                nt = glm::normalize(glm::vec3(nt.x * m.normal_scale, nt.y * m.normal_scale, nt.z));
            }
            const Quad& q = quads[p];
            const glm::vec3 N = glm::normalize(glm::cross(q.u, q.v)), T = glm::normalize(q.u),
                            B = glm::cross(N, T);
            const glm::vec3 n = glm::normalize(to_world * (T * nt.x + B * nt.y + N * nt.z));
            float ylm[9];
            math::sh_eval(3, n, ylm);
            glm::vec3 e(0.0f);
            for (int i = 0; i < 9; ++i)
                e += irradiance[i] * ylm[i];
            const glm::vec3 want = albedo * e / float(M_PI) + m.emissive_factor;
            ++compared[p];
            for (int ch = 0; ch < 3; ++ch)
                if (std::abs(color.at(x, y)[ch] - want[ch]) > 0.01f * std::abs(want[ch]) + 2e-3f &&
                    failures++ < 8)
                    ADD_FAILURE() << m.name << " pixel " << x << "," << y << " uv " << uv.x << "," << uv.y
                                  << " ch " << ch << ": GPU " << color.at(x, y)[ch] << ", CPU " << want[ch];
        }
    for (int p = 0; p < 3; ++p)
        EXPECT_GT(compared[p], 40) << "primitive " << p << " (" << asset.materials[size_t(p)].name
                                   << ") barely visible";
}
