// hemi's GLSL library (shaders/include/hemi/hemi.glsl) in an engine's own shader: tests/shaders/
// engine_surface.{vert,frag} declare their own vertex streams, descriptor sets (bindings of their own
// choosing), push constants and specialization constants, and compose the library's functions for each
// technique. Drawn over the same data hemi's own material system draws (the images hemi uploaded, handed
// out by TextureSet, TexelCoefficients and EnvironmentLighting), the two images agree at every covered
// pixel within 0.5% for every basis of math::bases() from a lightmap, a PRT object's per-vertex coefficients,
// an SH9 probe, radiosity normal mapping, SSBump and Heidrich & Seidel's four techniques; under validation.
// And hemi's vertex stage carries normals through the inverse transpose: a non-uniformly scaled object is lit
// with the normal an independent computation gives (mat3(model) fails it).
#include "../gpu_fixture.h"

#include "engine_pass.h"
#include "packed_mesh.h"

#include <hemi/bake/factored.h>
#include <hemi/gpu/commands.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/math/basis.h>
#include <hemi/math/brdf.h>
#include <hemi/math/camera.h>
#include <hemi/math/separable_basis.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/environment_lighting.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/gpu_mesh.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>

namespace
{
using namespace hemi;

class EngineShader : public test::GpuTest
{
};

constexpr uint32_t kSize = 96;
constexpr float kClear = -100.0f; // background: no technique produces it

// The engine's own uniform block and push constants (engine_surface.*).
struct EngineView
{
    glm::mat4 view_projection;
    glm::vec4 eye, light_direction, light_irradiance;
    glm::vec4 sep4_weights[9];
};
struct EnginePush
{
    glm::mat4 model;
    int32_t coefficient_offset = 0;
    int32_t pad[3] = {};
};

enum class Source
{
    Vertex = 0,
    Texel = 1,
    Probe = 2,
    Environment = 3
};

// A sphere with a bumpy normal map (its own tangents vary over it) and a colourful albedo map, seen from the
// side, one directional light.
struct Scene
{
    io::Mesh mesh;
    io::ImageRgba8 normal_map, albedo;
    glm::vec3 eye{0.6f, -3.2f, 0.9f};
    glm::vec3 light = glm::normalize(glm::vec3(0.4f, -0.7f, 0.6f));
    glm::vec3 irradiance{2.0f, 1.8f, 1.5f};

    // flat: a finer sphere, white and without relief (1 x 1 maps).
    explicit Scene(bool flat = false)
        : mesh(flat ? io::make_uv_sphere(1.0f, 96, 48) : io::make_uv_sphere(1.0f, 40, 20))
    {
        mesh.uvs1 = mesh.uvs;
        if (flat)
        {
            normal_map = {1, 1, {128, 128, 255, 255}};
            albedo = {1, 1, {255, 255, 255, 255}};
            return;
        }
        normal_map = {64, 32, std::vector<uint8_t>(64 * 32 * 4, 255)};
        for (uint32_t y = 0; y < 32; ++y)
            for (uint32_t x = 0; x < 64; ++x)
            {
                const float u = (x + 0.5f) / 64, v = (y + 0.5f) / 32;
                const glm::vec3 n =
                    glm::normalize(glm::vec3(0.5f * std::sin(25.1f * u), 0.4f * std::cos(18.8f * v), 1.0f));
                for (int c = 0; c < 3; ++c)
                    normal_map.pixels[(y * 64 + x) * 4 + c] =
                        uint8_t(std::lround((n[c] * 0.5f + 0.5f) * 255));
            }
        albedo = {32, 16, std::vector<uint8_t>(32 * 16 * 4, 255)};
        for (uint32_t y = 0; y < 16; ++y)
            for (uint32_t x = 0; x < 32; ++x)
            {
                uint8_t* p = &albedo.pixels[(y * 32 + x) * 4];
                p[0] = uint8_t(120 + 4 * x);
                p[1] = uint8_t(200 - 7 * y);
                p[2] = uint8_t(90 + ((x + y) % 5) * 30);
            }
    }
};

const Scene& scene()
{
    static const Scene s;
    return s;
}

// A smooth environment baked into 32^2 parabolic maps, one glossy map (exponent 20), one Fresnel table.
const io::EnvmapAsset& environment()
{
    static const io::EnvmapAsset env = []
    {
        io::ImageRgba img;
        img.width = 128;
        img.height = 64;
        img.pixels.resize(size_t(128) * 64 * 4);
        for (uint32_t y = 0; y < 64; ++y)
            for (uint32_t x = 0; x < 128; ++x)
            {
                const double phi = M_PI - 2 * M_PI * (x + 0.5) / 128, theta = M_PI * (y + 0.5) / 64;
                const glm::dvec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                   std::cos(theta));
                float* p = img.pixels.data() + (size_t(y) * 128 + x) * 4;
                p[0] = float(1.0 + 0.6 * d.x);
                p[1] = float(1.0 + 0.6 * d.y + 0.3 * d.x * d.y);
                p[2] = float(1.2 + 0.8 * d.z);
                p[3] = 1.0f;
            }
        bake::EnvmapBakeOptions o;
        o.size = 32;
        o.exponents = {20.0};
        o.iors = {1.5};
        return bake::bake_envmap(img, o);
    }();
    return env;
}

// Smooth coefficients, different per coefficient and channel, mostly positive (c0 dominant).
float coefficient(uint32_t k, uint32_t c, float u, float v)
{
    const float base = k == 0 ? 1.5f : 0.35f;
    return base * (0.8f + 0.5f * std::sin(3.0f * u + 1.7f * float(k) + 0.9f * float(c)) *
                              std::cos(2.0f * v + 0.6f * float(k)));
}

struct Case
{
    std::string name;
    render::Technique technique;
    Source source;
    int basis;
    int engine_technique; // engine_surface.frag's ENGINE_TECHNIQUE
};

struct Images
{
    std::vector<float> hemi, engine; // RGBA32F, kSize^2
};

// The case drawn by hemi's material system and by the engine's shader, each into a pass of its own.
Images draw_both(const Case& c, const glm::mat4& model = glm::mat4(1.0f), const Scene& s = scene(),
                 const std::vector<glm::vec3>& probe_override = {})
{
    gpu::Device& dev = test::device();
    const test::EnginePass hemi_pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    const test::EnginePass engine_pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = hemi_pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);

    // hemi's side: mesh, textures (image 0 the normal map, 1 the albedo), material, coefficient source.
    const render::GpuMesh mesh(dev, s.mesh, upload);
    io::Material material;
    material.normal.image = 0;
    material.normal.sampler.mipmaps = false;
    material.base_color.image = 1;
    material.base_color.sampler.mipmaps = false;
    const io::ImageRgba8 images[2] = {s.normal_map, s.albedo};
    render::TextureSet textures(dev, std::span<const io::ImageRgba8>(images, 2),
                                std::span<const io::Material>(&material, 1), upload);
    const render::MaterialInstance instance(system, textures, material, upload);
    const math::BasisDesc& basis = math::bases()[size_t(c.basis)];
    const uint32_t k = uint32_t(basis.size);

    std::unique_ptr<render::TexelCoefficients> texel;
    std::unique_ptr<render::VertexCoefficients> vertex;
    std::unique_ptr<render::ProbeBuffer> probe;
    std::unique_ptr<render::EnvironmentLighting> env;
    gpu::Buffer prt_buffer, probe_buffer, env_buffer;
    std::vector<glm::vec3> probe_values;
    render::EnvironmentMaterial env_material;
    env_material.kd = 0.6f;
    env_material.ks = 0.8f;
    env_material.world_to_env = glm::mat3(glm::rotate(glm::mat4(1.0f), 0.4f, glm::vec3(0.3f, 0.2f, 1.0f)));
    VkDescriptorSet source_set = VK_NULL_HANDLE;
    const uint32_t vertex_offset = 5 * k; // the object's texels start past another object's
    switch (c.source)
    {
    case Source::Texel:
    {
        const uint32_t w = 16, h = 8;
        std::vector<float> rgb(size_t(k) * w * h * 3);
        for (uint32_t i = 0; i < k; ++i)
            for (uint32_t y = 0; y < h; ++y)
                for (uint32_t x = 0; x < w; ++x)
                    for (uint32_t ch = 0; ch < 3; ++ch)
                        rgb[((i * h + y) * w + x) * 3 + ch] =
                            coefficient(i, ch, 6.28f * (x + 0.5f) / w, 3.14f * (y + 0.5f) / h);
        texel = std::make_unique<render::TexelCoefficients>(system, w, h, k, rgb, upload);
        source_set = texel->set();
        break;
    }
    case Source::Vertex:
    {
        const size_t texels = vertex_offset + s.mesh.vertex_count() * k;
        std::vector<glm::vec4> data(texels, glm::vec4(0.0f));
        for (size_t v = 0; v < s.mesh.vertex_count(); ++v)
            for (uint32_t i = 0; i < k; ++i)
                for (uint32_t ch = 0; ch < 3; ++ch)
                    data[vertex_offset + v * k + i][ch] =
                        coefficient(i, ch, 6.28f * s.mesh.uvs[v].x, 3.14f * s.mesh.uvs[v].y);
        prt_buffer =
            gpu::create_buffer(dev, {texels * sizeof(glm::vec4), VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT});
        gpu::write_buffer(dev, prt_buffer, data.data(), texels * sizeof(glm::vec4));
        vertex = std::make_unique<render::VertexCoefficients>(
            system, gpu::BufferRange{prt_buffer.handle(), 0, prt_buffer.size()}, texels);
        source_set = vertex->set();
        break;
    }
    case Source::Probe:
        probe_values = probe_override;
        for (uint32_t i = 0; i < 9 && probe_override.empty(); ++i)
            probe_values.push_back(glm::vec3(coefficient(i, 0, 0.3f, 0.2f), coefficient(i, 1, 0.3f, 0.2f),
                                             coefficient(i, 2, 0.3f, 0.2f)) *
                                   (i == 0 ? 2.0f : 1.0f));
        // Probe 2 of frame slot 1 of a buffer of 3 probes and 2 frames: the draw finds it by its offset.
        probe = std::make_unique<render::ProbeBuffer>(system, 3, 2);
        source_set = probe->set();
        break;
    case Source::Environment:
    {
        std::vector<math::BrdfTable> tables;
        if (c.technique == render::Technique::Banks)
            tables = {math::banks_table(30.0, 64)};
        else if (c.technique == render::Technique::Factored)
            tables = math::torrance_sparrow_tables(
                math::TorranceSparrow(math::FacetDistribution::Beckmann, 0.3, 1.5), 64);
        env = std::make_unique<render::EnvironmentLighting>(system, environment(), tables, env_material,
                                                            upload);
        source_set = env->set();
        break;
    }
    }

    render::MaterialKey key;
    key.technique = c.technique;
    key.basis = c.basis;
    key.source = c.source == Source::Vertex  ? render::CoefficientSourceKind::Vertex
                 : c.source == Source::Texel ? render::CoefficientSourceKind::Texel
                 : c.source == Source::Probe ? render::CoefficientSourceKind::Uniform
                                             : render::CoefficientSourceKind::Environment;
    key.frame = c.source == Source::Vertex || c.source == Source::Texel ? render::ShadingFrame::Tangent
                                                                        : render::ShadingFrame::World;
    const render::MaterialType& type = system.type(key);
    render::FrameSet frame_set(system);
    render::FrameData frame;
    frame.view_projection = math::look_at_projection(s.eye, glm::vec3(0.0f), 40.0f, 1.0f);
    frame.eye = s.eye;
    frame.lights = {{false, s.light, s.irradiance}};

    // The engine's side: its own vertex streams (positions; then normal, tangent, uv0, uv1 interleaved) and
    // 16-bit indices, its own sets over the images hemi uploaded, its own pipeline.
    const size_t n = s.mesh.vertex_count();
    struct Attributes
    {
        glm::vec3 normal;
        glm::vec4 tangent;
        glm::vec2 uv0, uv1;
    };
    std::vector<Attributes> attributes(n);
    for (size_t v = 0; v < n; ++v)
        attributes[v] = {s.mesh.normals[v], s.mesh.tangents[v], s.mesh.uvs[v], s.mesh.uvs1[v]};
    std::vector<uint16_t> indices(s.mesh.indices.begin(), s.mesh.indices.end());
    const gpu::Buffer positions =
        gpu::create_buffer(dev, {n * sizeof(glm::vec3), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    const gpu::Buffer attribute_buffer =
        gpu::create_buffer(dev, {n * sizeof(Attributes), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    const gpu::Buffer index_buffer =
        gpu::create_buffer(dev, {indices.size() * sizeof(uint16_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT});
    gpu::write_buffer(dev, positions, s.mesh.positions.data(), n * sizeof(glm::vec3));
    gpu::write_buffer(dev, attribute_buffer, attributes.data(), n * sizeof(Attributes));
    gpu::write_buffer(dev, index_buffer, indices.data(), indices.size() * sizeof(uint16_t));

    EngineView view{};
    view.view_projection = frame.view_projection;
    view.eye = glm::vec4(s.eye, 1.0f);
    view.light_direction = glm::vec4(s.light, 0.0f);
    view.light_irradiance = glm::vec4(s.irradiance, 0.0f);
    for (int r = 0; r < 9; ++r)
        view.sep4_weights[r] = glm::vec4(math::sep4_weights()[r * 4], math::sep4_weights()[r * 4 + 1],
                                         math::sep4_weights()[r * 4 + 2], math::sep4_weights()[r * 4 + 3]);
    const gpu::Buffer view_buffer =
        gpu::create_buffer(dev, {sizeof view, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
    gpu::write_buffer(dev, view_buffer, &view, sizeof view);

    const VkShaderStageFlags fragment = VK_SHADER_STAGE_FRAGMENT_BIT;
    const std::vector<gpu::Binding> view_bindings = {
        {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_SHADER_STAGE_VERTEX_BIT | fragment}};
    std::vector<gpu::Binding> object_bindings = {{3, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fragment},
                                                 {5, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fragment}};
    std::vector<gpu::DescriptorWrite> writes(2);
    writes[0].binding = 3;
    writes[0].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[0].image = {textures.sampler(material.base_color.sampler), textures.image(1, true).view(),
                       VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    writes[1].binding = 5;
    writes[1].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[1].image = {textures.sampler(material.normal.sampler), textures.image(0, false).view(),
                       VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    auto image_write = [&](uint32_t binding, VkSampler sampler, const gpu::Image& image)
    {
        object_bindings.push_back({binding, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, fragment});
        gpu::DescriptorWrite w;
        w.binding = binding;
        w.type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        w.image = {sampler, image.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
        writes.push_back(w);
    };
    auto buffer_write = [&](uint32_t binding, const gpu::Buffer& buffer)
    {
        object_bindings.push_back({binding, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, fragment});
        gpu::DescriptorWrite w;
        w.binding = binding;
        w.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
        w.buffer = {buffer, 0, VK_WHOLE_SIZE};
        writes.push_back(w);
    };
    gpu::BufferView prt_view;
    std::string fragment_shader;
    switch (c.source)
    {
    case Source::Texel:
        image_write(7, texel->sampler(), texel->pages());
        image_write(13, texel->table_sampler(), texel->page_table());
        fragment_shader = "engine_texel.frag";
        break;
    case Source::Vertex:
    {
        object_bindings.push_back({7, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, VK_SHADER_STAGE_VERTEX_BIT});
        prt_view = gpu::create_buffer_view(dev, prt_buffer, VK_FORMAT_R32G32B32A32_SFLOAT, 0, VK_WHOLE_SIZE);
        gpu::DescriptorWrite w;
        w.binding = 7;
        w.type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
        w.texel_view = prt_view;
        writes.push_back(w);
        fragment_shader = "engine_vertex.frag";
        break;
    }
    case Source::Probe:
    {
        glm::vec4 sh[9];
        for (int i = 0; i < 9; ++i)
            sh[i] = glm::vec4(probe_values[i], 0.0f);
        probe_buffer = gpu::create_buffer(dev, {sizeof sh, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
        gpu::write_buffer(dev, probe_buffer, sh, sizeof sh);
        buffer_write(7, probe_buffer);
        fragment_shader = "engine_probe.frag";
        break;
    }
    case Source::Environment:
    {
        const shared::EnvironmentUniforms u = env->uniforms(env_material);
        env_buffer = gpu::create_buffer(dev, {sizeof u, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT});
        gpu::write_buffer(dev, env_buffer, &u, sizeof u);
        buffer_write(7, env_buffer);
        image_write(8, env->sampler(), env->mirror_map());
        image_write(9, env->sampler(), env->glossy_map());
        image_write(10, env->sampler(), env->diffuse_map());
        image_write(11, env->sampler(), env->fresnel_table());
        image_write(12, env->sampler(), env->brdf_tables());
        fragment_shader = "engine_environment.frag";
        break;
    }
    }
    const gpu::DescriptorSetLayout view_layout = gpu::create_set_layout(dev, view_bindings);
    const gpu::DescriptorSetLayout object_layout = gpu::create_set_layout(dev, object_bindings);
    std::vector<gpu::Binding> all = view_bindings;
    all.insert(all.end(), object_bindings.begin(), object_bindings.end());
    const gpu::DescriptorPool pool = gpu::create_descriptor_pool(dev, all, 2);
    const VkDescriptorSet view_set = gpu::allocate_descriptor_set(dev, pool, view_layout);
    const VkDescriptorSet object_set = gpu::allocate_descriptor_set(dev, pool, object_layout);
    gpu::DescriptorWrite view_write;
    view_write.binding = 0;
    view_write.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    view_write.buffer = {view_buffer, 0, VK_WHOLE_SIZE};
    gpu::write_descriptors(dev, view_set, std::span<const gpu::DescriptorWrite>(&view_write, 1));
    gpu::write_descriptors(dev, object_set, writes);

    gpu::GraphicsProgramDesc desc;
    desc.vertex_shader =
        test::test_spirv(c.source == Source::Vertex ? "engine_vertex.vert" : "engine_other.vert");
    desc.fragment_shader = test::test_spirv(fragment_shader);
    desc.set_layouts = {view_layout, object_layout};
    desc.push_constant_size = sizeof(EnginePush);
    desc.specialization = {uint32_t(c.engine_technique), uint32_t(c.basis), k};
    desc.vertex_bindings = {{0, sizeof(glm::vec3), VK_VERTEX_INPUT_RATE_VERTEX},
                            {1, sizeof(Attributes), VK_VERTEX_INPUT_RATE_VERTEX}};
    desc.vertex_attributes = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0},
                              {1, 1, VK_FORMAT_R32G32B32_SFLOAT, offsetof(Attributes, normal)},
                              {2, 1, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(Attributes, tangent)},
                              {3, 1, VK_FORMAT_R32G32_SFLOAT, offsetof(Attributes, uv0)},
                              {4, 1, VK_FORMAT_R32G32_SFLOAT, offsetof(Attributes, uv1)}};
    desc.render_pass = engine_pass.render_pass;
    const gpu::Program program = gpu::create_graphics_program(dev, desc);

    const float clear[4] = {kClear, kClear, kClear, kClear};
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      upload.record(cmd);
                      frame_set.record_update(cmd, frame);
                      if (probe)
                          probe->record_update(cmd, 1, 2, probe_values);
                      hemi_pass.begin(cmd, clear);
                      render::DrawBindings b;
                      b.type = &type;
                      b.frame = frame_set.set();
                      b.material = instance.set();
                      b.source = source_set;
                      b.push.model = model;
                      b.push.coefficient_offset = probe ? probe->offset(1, 2) : vertex_offset;
                      render::bind_material(cmd, b);
                      mesh.bind(cmd);
                      mesh.draw(cmd, 0, mesh.index_count());
                      vkCmdEndRenderPass(cmd);

                      engine_pass.begin(cmd, clear);
                      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
                      const VkDescriptorSet sets[2] = {view_set, object_set};
                      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0, 2,
                                              sets, 0, nullptr);
                      EnginePush push;
                      push.model = model;
                      push.coefficient_offset = int32_t(vertex_offset);
                      vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof push, &push);
                      const VkBuffer streams[2] = {positions, attribute_buffer};
                      const VkDeviceSize offsets[2] = {0, 0};
                      vkCmdBindVertexBuffers(cmd, 0, 2, streams, offsets);
                      vkCmdBindIndexBuffer(cmd, index_buffer, 0, VK_INDEX_TYPE_UINT16);
                      vkCmdDrawIndexed(cmd, uint32_t(indices.size()), 1, 0, 0, 0);
                      vkCmdEndRenderPass(cmd);
                  });
    return {hemi_pass.read_color(), engine_pass.read_color()};
}

struct Agreement
{
    int covered = 0, mismatched_coverage = 0, outside = 0;
    float worst = 0.0f; // largest |difference| / (|reference| + 1e-3)
};
// Every covered pixel: |engine - hemi| <= 0.5% of |hemi| + 1e-4 per channel.
Agreement agree(const std::vector<float>& reference, const std::vector<float>& got)
{
    Agreement a;
    for (size_t p = 0; p < size_t(kSize) * kSize; ++p)
    {
        const float* r = &reference[p * 4];
        const float* g = &got[p * 4];
        const bool rc = r[3] != kClear, gc = g[3] != kClear;
        if (rc != gc)
        {
            ++a.mismatched_coverage;
            continue;
        }
        if (!rc)
            continue;
        ++a.covered;
        bool bad = false;
        for (int ch = 0; ch < 3; ++ch)
        {
            const float d = std::abs(g[ch] - r[ch]);
            a.worst = std::max(a.worst, d / (std::abs(r[ch]) + 1e-3f));
            bad = bad || d > 0.005f * std::abs(r[ch]) + 1e-4f;
        }
        a.outside += bad;
    }
    return a;
}

} // namespace

TEST_F(EngineShader, RendersWhatHemisMaterialRendersForEveryBasisAndTechnique)
{
    std::vector<Case> cases;
    for (const math::BasisDesc& b : math::bases())
        cases.push_back(
            {"lightmap " + std::string(b.name), render::Technique::Irradiance, Source::Texel, b.id, 0});
    cases.push_back(
        {"prt sh9 (per vertex)", render::Technique::Irradiance, Source::Vertex, HEMI_BASIS_SH9, 0});
    cases.push_back({"prt h6 (per vertex)", render::Technique::Irradiance, Source::Vertex, HEMI_BASIS_H6, 0});
    cases.push_back({"probe sh9", render::Technique::Irradiance, Source::Probe, HEMI_BASIS_SH9, 0});
    cases.push_back({"rnm", render::Technique::Rnm, Source::Texel, HEMI_BASIS_HL2, 1});
    cases.push_back({"ssbump", render::Technique::Ssbump, Source::Texel, HEMI_BASIS_HL2, 2});
    cases.push_back({"factored", render::Technique::Factored, Source::Environment, HEMI_BASIS_SH9, 3});
    cases.push_back({"banks", render::Technique::Banks, Source::Environment, HEMI_BASIS_SH9, 4});
    cases.push_back({"env_mirror", render::Technique::EnvMirror, Source::Environment, HEMI_BASIS_SH9, 5});
    cases.push_back({"env_glossy", render::Technique::EnvGlossy, Source::Environment, HEMI_BASIS_SH9, 6});

    std::vector<float> previous;
    for (const Case& c : cases)
    {
        const Images images = draw_both(c);
        const Agreement a = agree(images.hemi, images.engine);
        std::printf("%-22s %5d pixels, %d outside 0.5%%, worst relative difference %.2e\n", c.name.c_str(),
                    a.covered, a.outside, double(a.worst));
        EXPECT_GT(a.covered, 2000) << c.name;
        EXPECT_EQ(a.mismatched_coverage, 0) << c.name;
        EXPECT_EQ(a.outside, 0) << c.name;
        // The comparison can tell cases apart: the previous case's image fails it at many pixels (an engine
        // shader that ignored the basis or the technique would not pass).
        if (!previous.empty())
        {
            const Agreement other = agree(previous, images.engine);
            EXPECT_GT(other.outside, other.covered / 4) << c.name << " looks like the case before it";
        }
        previous = images.hemi;
    }
}

// A probe-lit white sphere scaled by (1.6, 1, 0.5) and turned: each pixel shows the normal hemi lit it with,
// because the probe's irradiance is linear in the normal, colour = 1 + 0.8 n per channel (bands 0 and 1
// only). The reference normal comes from casting the pixel's ray at the ellipsoid on the CPU (the unit
// sphere's point p in object space, normal M^-T p). mat3(model) p, what hemi's vertex stage used before, is
// tens of degrees away over most of the ellipsoid.
TEST_F(EngineShader, NonUniformScaleLightsWithTheInverseTransposeNormal)
{
    Scene flat(true);
    flat.irradiance = glm::vec3(0.0f); // the probe alone: the colour is linear in the normal
    const glm::mat4 model = glm::rotate(glm::mat4(1.0f), 0.5f, glm::vec3(0, 0, 1)) *
                            glm::scale(glm::mat4(1.0f), glm::vec3(1.6f, 1.0f, 0.5f));
    const float pi = float(M_PI), y00 = 0.2820948f, y1 = 0.4886025f;
    std::vector<glm::vec3> probe(9, glm::vec3(0.0f));
    probe[0] = glm::vec3(pi / y00);
    probe[3].r = -0.8f * pi / y1; // b_3 = -Y1 n.x
    probe[1].g = -0.8f * pi / y1; // b_1 = -Y1 n.y
    probe[2].b = 0.8f * pi / y1;  // b_2 = Y1 n.z
    const Case c{"probe sh9, scaled", render::Technique::Irradiance, Source::Probe, HEMI_BASIS_SH9, 0};
    const Images images = draw_both(c, model, flat, probe);
    const Agreement a = agree(images.hemi, images.engine);
    EXPECT_GT(a.covered, 2000);
    EXPECT_EQ(a.outside, 0) << "the engine shader's normal matrix differs from hemi's";

    const glm::mat4 vp = math::look_at_projection(flat.eye, glm::vec3(0.0f), 40.0f, 1.0f);
    const glm::mat4 to_object = glm::inverse(vp * model);
    const glm::mat3 m(model), inverse_transpose = glm::transpose(glm::inverse(glm::mat3(model)));
    int checked = 0, right = 0, naive_right = 0;
    float worst = 0.0f;
    for (uint32_t y = 0; y < kSize; ++y)
        for (uint32_t x = 0; x < kSize; ++x)
        {
            const float* px = &images.hemi[(size_t(y) * kSize + x) * 4];
            if (px[3] == kClear)
                continue;
            // The pixel centre's ray in object space, against the unit sphere.
            const glm::vec2 ndc((x + 0.5f) / kSize * 2.0f - 1.0f, (y + 0.5f) / kSize * 2.0f - 1.0f);
            const glm::vec4 a0 = to_object * glm::vec4(ndc, 0.0f, 1.0f),
                            a1 = to_object * glm::vec4(ndc, 1.0f, 1.0f);
            const glm::vec3 o = glm::vec3(a0) / a0.w, d = glm::normalize(glm::vec3(a1) / a1.w - o);
            const float b = glm::dot(o, d), disc = b * b - (glm::dot(o, o) - 1.0f);
            if (disc < 0.0f)
                continue;
            const glm::vec3 p = o + d * (-b - std::sqrt(disc));
            const glm::vec3 true_n = glm::normalize(inverse_transpose * p), naive_n = glm::normalize(m * p);
            const glm::vec3 world = glm::vec3(model * glm::vec4(p, 1.0f));
            if (glm::dot(true_n, glm::normalize(flat.eye - world)) < 0.3f)
                continue; // near the silhouette the tessellation shows
            const glm::vec3 got = glm::normalize((glm::vec3(px[0], px[1], px[2]) - 1.0f) / 0.8f);
            const float angle = std::acos(std::min(1.0f, glm::dot(got, true_n))) * 180.0f / pi;
            const float naive_angle = std::acos(std::min(1.0f, glm::dot(naive_n, true_n))) * 180.0f / pi;
            ++checked;
            right += angle < 2.0f;
            naive_right += naive_angle < 2.0f;
            worst = std::max(worst, angle);
        }
    std::printf("%d pixels: %d within 2 degrees of the ellipsoid's normal (worst %.2f); mat3(model) would "
                "give %d\n",
                checked, right, double(worst), naive_right);
    EXPECT_GT(checked, 1000);
    EXPECT_EQ(right, checked);
    EXPECT_LT(naive_right, checked / 2) << "the scale does not tell the two normal transforms apart";
}

namespace
{
class EngineData : public test::GpuTest
{
};

// The scene's sphere drawn through hemi's material system with an H6 lightmap (tangent frame: normal,
// tangent, both UV sets matter), the mesh's buffers bound by `bind` (which returns the index count).
std::vector<float>
draw_lightmapped(const render::VertexLayout& layout, const std::function<uint32_t(VkCommandBuffer)>& bind,
                 const std::function<render::MaterialTextures(render::TextureSet&)>& engine = {})
{
    gpu::Device& dev = test::device();
    const Scene& s = scene();
    const test::EnginePass pass(kSize, kSize, {VK_FORMAT_R32G32B32A32_SFLOAT});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    gpu::UploadBatch upload(dev);
    io::Material material;
    material.normal.image = 0;
    material.normal.sampler.mipmaps = false;
    material.base_color.image = 1;
    material.base_color.sampler.mipmaps = false;
    const io::ImageRgba8 images[2] = {s.normal_map, s.albedo};
    render::TextureSet textures(dev, std::span<const io::ImageRgba8>(images, 2),
                                std::span<const io::Material>(&material, 1), upload);
    const render::MaterialInstance instance(system, textures, material, upload,
                                            engine ? engine(textures) : render::MaterialTextures{});
    const uint32_t k = 6, w = 16, h = 8;
    std::vector<float> rgb(size_t(k) * w * h * 3);
    for (uint32_t i = 0; i < k; ++i)
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x)
                for (uint32_t ch = 0; ch < 3; ++ch)
                    rgb[((i * h + y) * w + x) * 3 + ch] =
                        coefficient(i, ch, 6.28f * (x + 0.5f) / w, 3.14f * (y + 0.5f) / h);
    const render::TexelCoefficients lightmap(system, w, h, k, rgb, upload);
    render::MaterialKey key;
    key.source = render::CoefficientSourceKind::Texel;
    key.basis = HEMI_BASIS_H6;
    key.vertex = layout;
    const render::MaterialType& type = system.type(key);
    render::FrameSet frame_set(system);
    render::FrameData frame;
    frame.view_projection = math::look_at_projection(s.eye, glm::vec3(0.0f), 40.0f, 1.0f);
    frame.eye = s.eye;
    const float clear[4] = {kClear, kClear, kClear, kClear};
    gpu::one_shot(dev,
                  [&](VkCommandBuffer cmd)
                  {
                      upload.record(cmd);
                      frame_set.record_update(cmd, frame);
                      pass.begin(cmd, clear);
                      render::DrawBindings b;
                      b.type = &type;
                      b.frame = frame_set.set();
                      b.material = instance.set();
                      b.source = lightmap.set();
                      b.push.model = glm::mat4(1.0f);
                      render::bind_material(cmd, b);
                      vkCmdDrawIndexed(cmd, bind(cmd), 1, 0, 0, 0);
                      vkCmdEndRenderPass(cmd);
                  });
    return pass.read_color();
}

// hemi's own layout: a GpuMesh.
std::vector<float>
draw_with_gpu_mesh(const std::function<render::MaterialTextures(render::TextureSet&)>& engine = {},
                   const io::Mesh& m = scene().mesh)
{
    gpu::UploadBatch upload(test::device());
    const render::GpuMesh mesh(test::device(), m, upload);
    upload.submit_and_wait();
    return draw_lightmapped(
        render::GpuMesh::layout(),
        [&](VkCommandBuffer cmd)
        {
            mesh.bind(cmd);
            return mesh.index_count();
        },
        engine);
}

} // namespace

// The sphere in an engine's packed layout (packed_mesh.h), two streams: positions as fp16 RGBA (8 bytes) in
// stream 0; normal and tangent as snorm16 RGBA, then both fp32 UV sets in stream 1 (32 bytes); 16-bit
// indices. Drawn through a material key with that layout, it equals the GpuMesh's fp32 drawing of the same
// values (the packed ones widened on the CPU: the comparison is of the data path, not of the quantisation,
// which moves pixel centres' barycentrics by enough to change steep texture lookups by 1%).
TEST_F(EngineData, MeshInTheEnginesOwnLayoutDrawsLikeHemisLayout)
{
    gpu::Device& dev = test::device();
    const test::PackedMesh packed = test::pack_mesh(scene().mesh);
    const std::vector<uint16_t>& positions = packed.positions;
    const std::vector<uint16_t>& indices = packed.indices;
    const io::Mesh& same = packed.widened; // the packed values, widened
    const gpu::Buffer stream0 =
        gpu::create_buffer(dev, {positions.size() * 2, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    const gpu::Buffer stream1 = gpu::create_buffer(
        dev, {packed.attributes.size() * sizeof(test::PackedAttributes), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT});
    const gpu::Buffer index_buffer =
        gpu::create_buffer(dev, {indices.size() * 2, VK_BUFFER_USAGE_INDEX_BUFFER_BIT});
    gpu::write_buffer(dev, stream0, positions.data(), positions.size() * 2);
    gpu::write_buffer(dev, stream1, packed.attributes.data(), stream1.size());
    gpu::write_buffer(dev, index_buffer, indices.data(), indices.size() * 2);

    const render::VertexLayout layout = test::PackedMesh::layout();
    const std::vector<float> engine =
        draw_lightmapped(layout,
                         [&](VkCommandBuffer cmd)
                         {
                             const VkBuffer streams[2] = {stream0, stream1};
                             const VkDeviceSize offsets[2] = {0, 0};
                             vkCmdBindVertexBuffers(cmd, 0, 2, streams, offsets);
                             vkCmdBindIndexBuffer(cmd, index_buffer, 0, VK_INDEX_TYPE_UINT16);
                             return uint32_t(indices.size());
                         });
    const std::vector<float> reference = draw_with_gpu_mesh({}, same);
    const Agreement a = agree(reference, engine);
    std::printf("%d pixels, %d outside 0.5%%, worst relative difference %.2e\n", a.covered, a.outside,
                double(a.worst));
    EXPECT_GT(a.covered, 4000);
    EXPECT_EQ(a.mismatched_coverage, 0);
    EXPECT_EQ(a.outside, 0);

    // A layout the device cannot read, or a stream without a stride, is refused when the type is made.
    render::RenderTargetDesc target;
    const test::EnginePass pass(8, 8, {VK_FORMAT_R32G32B32A32_SFLOAT});
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    render::MaterialKey key;
    key.vertex = layout;
    key.vertex.strides[1] = 0;
    EXPECT_THROW(
        {
            try
            {
                system.type(key);
            }
            catch (const std::invalid_argument& e)
            {
                EXPECT_NE(std::string(e.what()).find("normal is in stream 1, which has no stride"),
                          std::string::npos)
                    << e.what();
                throw;
            }
        },
        std::invalid_argument);
    key.vertex = layout;
    key.vertex.uv0.format = VK_FORMAT_D32_SFLOAT;
    EXPECT_THROW(system.type(key), std::invalid_argument);
}

// A material whose base colour and normal map are the engine's own images (uploaded by the engine, its own
// views and samplers) draws what the same material loaded through a TextureSet draws.
TEST_F(EngineData, MaterialFromTheEnginesOwnImageViewsEqualsTheTextureSetOne)
{
    gpu::Device& dev = test::device();
    const Scene& s = scene();
    auto own_image = [&](const io::ImageRgba8& img, VkFormat format)
    {
        gpu::Image image =
            gpu::create_image(dev, {img.width, img.height, format, VK_IMAGE_USAGE_SAMPLED_BIT});
        gpu::upload_image(dev, image, img.pixels.data(), img.pixels.size(),
                          VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        return image;
    };
    const gpu::Image albedo = own_image(s.albedo, VK_FORMAT_R8G8B8A8_SRGB);
    const gpu::Image normal = own_image(s.normal_map, VK_FORMAT_R8G8B8A8_UNORM);
    const gpu::Sampler sampler = gpu::create_sampler(
        dev, {VK_FILTER_LINEAR, VK_SAMPLER_MIPMAP_MODE_NEAREST, VK_SAMPLER_ADDRESS_MODE_REPEAT, 0.0f});
    const std::vector<float> engine = draw_with_gpu_mesh(
        [&](render::TextureSet&)
        {
            render::MaterialTextures t;
            t.base_color = {albedo.view(), sampler};
            t.normal = {normal.view(), sampler};
            return t;
        });
    const std::vector<float> reference = draw_with_gpu_mesh();
    const Agreement a = agree(reference, engine);
    std::printf("%d pixels, %d outside 0.5%%, worst relative difference %.2e\n", a.covered, a.outside,
                double(a.worst));
    EXPECT_GT(a.covered, 4000);
    EXPECT_EQ(a.mismatched_coverage, 0);
    EXPECT_EQ(a.outside, 0);
    // The engine's images are what is drawn: swapping its two views changes the picture.
    const std::vector<float> swapped = draw_with_gpu_mesh(
        [&](render::TextureSet&)
        {
            render::MaterialTextures t;
            t.base_color = {normal.view(), sampler};
            t.normal = {albedo.view(), sampler};
            return t;
        });
    EXPECT_GT(agree(reference, swapped).outside, a.covered / 4);
}

// ProbeBuffer::write puts a probe's coefficients where offset(frame, probe) says (the vec4 index the surface
// shader reads, checked by the probe case above through record_update), zero-fills the rest of the probe
// and touches no other probe or frame slot; the fourth components of the first four hold the occlusion of the
// mixed lights (1 unless given; outside [0, 1] refused).
TEST_F(EngineShader, ProbeBufferWritesEachProbeOfEachFrameAtItsOffset)
{
    const gpu::Device& dev = hemi::test::device();
    const test::EnginePass pass(8, 8, {VK_FORMAT_R8G8B8A8_UNORM});
    render::RenderTargetDesc target;
    target.render_pass = pass.render_pass;
    render::MaterialSystem system(dev, target);
    render::ProbeBuffer probes(system, 3, 2);
    const glm::vec4* mapped = static_cast<const glm::vec4*>(probes.buffer().mapped());
    ASSERT_NE(mapped, nullptr);
    for (uint32_t f = 0; f < 2; ++f)
        for (uint32_t p = 0; p < 3; ++p)
        {
            const std::vector<glm::vec3> c = {glm::vec3(float(f), float(p), 1.0f),
                                              glm::vec3(float(f * 10 + p))};
            // The mixed lights' occlusion in the fourth components of the first four (1 by default).
            if (p == 1)
                probes.write(f, p, c, {0.5f, 0.25f, 0.125f, 0.0f});
            else
                probes.write(f, p, c);
        }
    for (uint32_t f = 0; f < 2; ++f)
        for (uint32_t p = 0; p < 3; ++p)
        {
            const uint32_t at = probes.offset(f, p);
            const std::array<float, 4> o =
                p == 1 ? std::array<float, 4>{0.5f, 0.25f, 0.125f, 0.0f} : std::array<float, 4>{1, 1, 1, 1};
            EXPECT_EQ(at, (f * 3 + p) * uint32_t(HEMI_BASIS_MAX_SIZE));
            EXPECT_EQ(mapped[at], glm::vec4(float(f), float(p), 1.0f, o[0]));
            EXPECT_EQ(mapped[at + 1], glm::vec4(glm::vec3(float(f * 10 + p)), o[1]));
            for (uint32_t k = 2; k < HEMI_BASIS_MAX_SIZE; ++k)
                EXPECT_EQ(mapped[at + k], glm::vec4(0.0f, 0.0f, 0.0f, k < 4 ? o[k] : 0.0f));
        }
    EXPECT_THROW(probes.offset(2, 0), std::invalid_argument);
    EXPECT_THROW(probes.write(0, 3, {}), std::invalid_argument);
    EXPECT_THROW(probes.write(0, 0, {}, {1.0f, 1.5f, 1.0f, 1.0f}), std::invalid_argument);
}
