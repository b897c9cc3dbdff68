#include "renderer.h"
#include "vulkan.h"

#include <hemi/gpu/upload.h>
#include <hemi/io/image.h>
#include <hemi/math/camera.h>
#include <hemi/math/luminance.h>
#include <hemi/render/access.h>
#include <hemi/render/material/environment_lighting.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/scene/lightmap_model.h>
#include <hemi/render/scene/prt_model.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

// The sample's shaders, compiled by glslang at build time and embedded (hemi_add_shaders TABLE).
namespace hemi::shaders::detail
{
struct EmbeddedShader
{
    std::string_view name;
    const uint32_t* code;
    size_t words;
};
extern const EmbeddedShader kEngineShaders[];
extern const size_t kEngineShadersCount;
} // namespace hemi::shaders::detail

namespace engine
{
namespace
{
using namespace hemi;

std::span<const uint32_t> spirv(std::string_view name)
{
    for (size_t i = 0; i < shaders::detail::kEngineShadersCount; ++i)
        if (shaders::detail::kEngineShaders[i].name == name)
            return {shaders::detail::kEngineShaders[i].code, shaders::detail::kEngineShaders[i].words};
    throw std::logic_error("engine sample: no shader " + std::string(name));
}

constexpr uint32_t kFramesInFlight = 2;
constexpr uint32_t kShadowSize = 1024;
constexpr uint32_t kSpheres = 3;
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr VkFormat kHdrFormat = VK_FORMAT_R16G16B16A16_SFLOAT;

// shaders/frame.glsl's EngineFrame (std140) and EngineObject.
struct EngineFrame
{
    glm::mat4 view_projection;
    glm::mat4 sun_view_projection;
    glm::vec4 eye, sun_direction, sun_irradiance, shadow, fog;
    glm::ivec4 mode;
    glm::mat4 world_to_level;
    glm::vec4 reflection_centre, reflection_min, reflection_max;
    shared::EnvironmentUniforms env;
};
struct EngineObject
{
    glm::mat4 model;
    glm::vec4 albedo{1.0f};
    glm::ivec4 index{0};
    glm::vec4 material{0.0f}; // GGX roughness (0: none), f0, the probes' occlusion of the mixed sun
};
static_assert(sizeof(EngineObject) <= 128, "push constants beyond Vulkan's guaranteed 128 bytes");

// The polished floor's coat (the level's material of that name): a dielectric (f0 0.04) of roughness 0.3.
constexpr float kFloorRoughness = 0.3f, kFloorF0 = 0.04f;
constexpr float kShadowFade = 1.5f; // the band before the shadow distance where the shadow map fades out
struct PostPush
{
    float exposure;
    int32_t tonemap, encode;
};

// A render pass of the engine's graph: colour attachments (format, final layout) and an optional depth
// attachment, each with its load op; the dependencies say what comes before and after within a frame.
struct AttachmentSpec
{
    VkFormat format;
    VkAttachmentLoadOp load;
    VkImageLayout initial, final;
};
VkRenderPass make_render_pass(VkDevice device, const std::vector<AttachmentSpec>& colors,
                              const AttachmentSpec* depth,
                              const std::vector<VkSubpassDependency>& dependencies)
{
    std::vector<VkAttachmentDescription> attachments;
    std::vector<VkAttachmentReference> color_refs;
    for (const AttachmentSpec& c : colors)
    {
        color_refs.push_back({uint32_t(attachments.size()), VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL});
        attachments.push_back({0, c.format, VK_SAMPLE_COUNT_1_BIT, c.load, VK_ATTACHMENT_STORE_OP_STORE,
                               VK_ATTACHMENT_LOAD_OP_DONT_CARE, VK_ATTACHMENT_STORE_OP_DONT_CARE, c.initial,
                               c.final});
    }
    VkAttachmentReference depth_ref{uint32_t(attachments.size()),
                                    VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    if (depth)
        attachments.push_back({0, depth->format, VK_SAMPLE_COUNT_1_BIT, depth->load,
                               VK_ATTACHMENT_STORE_OP_STORE, VK_ATTACHMENT_LOAD_OP_DONT_CARE,
                               VK_ATTACHMENT_STORE_OP_DONT_CARE, depth->initial, depth->final});
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = uint32_t(color_refs.size());
    subpass.pColorAttachments = color_refs.data();
    subpass.pDepthStencilAttachment = depth ? &depth_ref : nullptr;
    VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    info.attachmentCount = uint32_t(attachments.size());
    info.pAttachments = attachments.data();
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = uint32_t(dependencies.size());
    info.pDependencies = dependencies.data();
    VkRenderPass pass;
    check(vkCreateRenderPass(device, &info, nullptr, &pass), "vkCreateRenderPass");
    return pass;
}

VkFramebuffer make_framebuffer(VkDevice device, VkRenderPass pass, const std::vector<VkImageView>& views,
                               VkExtent2D extent)
{
    VkFramebufferCreateInfo info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    info.renderPass = pass;
    info.attachmentCount = uint32_t(views.size());
    info.pAttachments = views.data();
    info.width = extent.width;
    info.height = extent.height;
    info.layers = 1;
    VkFramebuffer fb;
    check(vkCreateFramebuffer(device, &info, nullptr, &fb), "vkCreateFramebuffer");
    return fb;
}

void set_viewport(VkCommandBuffer cmd, VkExtent2D e)
{
    const VkViewport viewport{0.0f, 0.0f, float(e.width), float(e.height), 0.0f, 1.0f};
    const VkRect2D scissor{{0, 0}, e};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
}

// Whether an axis-aligned box (model space) under `model` can be seen through `view_projection`: no clip
// plane has all eight corners outside it.
bool visible(const glm::mat4& view_projection, const glm::mat4& model, glm::vec3 lo, glm::vec3 hi)
{
    const glm::mat4 m = view_projection * model;
    glm::vec4 corners[8];
    for (int i = 0; i < 8; ++i)
        corners[i] = m * glm::vec4(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z, 1.0f);
    for (int plane = 0; plane < 5; ++plane) // x < -w, x > w, y < -w, y > w, z > w
    {
        bool all_out = true;
        for (const glm::vec4& c : corners)
        {
            const float d = plane == 0   ? c.x + c.w
                            : plane == 1 ? c.w - c.x
                            : plane == 2 ? c.y + c.w
                            : plane == 3 ? c.w - c.y
                                         : c.w - c.z;
            all_out = all_out && d < 0.0f;
        }
        if (all_out)
            return false;
    }
    return true;
}

// The sun's shadow map: an orthographic view along the sun's light over the level's bounding sphere (Vulkan
// clip space, y down, as hemi's cameras).
glm::mat4 sun_matrix(const glm::vec3& towards_sun, const math::BoundingSphere& b)
{
    const float r = b.radius;
    const glm::vec3 up =
        std::abs(towards_sun.z) > 0.99f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 0.0f, 1.0f);
    const glm::mat4 view = glm::lookAt(b.centre + 2.0f * r * towards_sun, b.centre, up);
    glm::mat4 proj = glm::orthoRH_ZO(-r, r, -r, r, 0.5f * r, 3.5f * r);
    proj[1][1] *= -1.0f;
    return proj * view;
}

// The engine's vertex format: positions alone in stream 0 (all its depth-only passes bind), the rest in
// stream 1; 32-bit indices. Every mesh of the scene lies once in these buffers: hemi is told the layout and
// the ranges (render::EngineGeometry) and its depth and shadow pipelines draw from them too.
struct VertexRest
{
    glm::vec3 normal;
    glm::vec4 tangent;
    glm::vec2 uv0, uv1;
};
static_assert(sizeof(VertexRest) == 44);

render::VertexLayout engine_layout()
{
    render::VertexLayout l;
    l.position = {0, VK_FORMAT_R32G32B32_SFLOAT, 0};
    l.normal = {1, VK_FORMAT_R32G32B32_SFLOAT, uint32_t(offsetof(VertexRest, normal))};
    l.tangent = {1, VK_FORMAT_R32G32B32A32_SFLOAT, uint32_t(offsetof(VertexRest, tangent))};
    l.uv0 = {1, VK_FORMAT_R32G32_SFLOAT, uint32_t(offsetof(VertexRest, uv0))};
    l.uv1 = {1, VK_FORMAT_R32G32_SFLOAT, uint32_t(offsetof(VertexRest, uv1))};
    l.strides[0] = sizeof(glm::vec3);
    l.strides[1] = sizeof(VertexRest);
    return l;
}

// Where one mesh lies in the engine's buffers.
struct MeshRange
{
    uint32_t base_vertex = 0, first_index = 0, index_count = 0;
};

// A pipeline and its layout.
struct Program
{
    VkPipeline pipeline = VK_NULL_HANDLE;
    VkPipelineLayout layout = VK_NULL_HANDLE;
};

} // namespace

struct Renderer::Impl
{
    Context& ctx;
    Swapchain& swapchain;
    const samples::EngineAssets& assets;
    gpu::Device device;
    VkDevice vk;
    Memory memory;
    VkCommandPool command_pool = VK_NULL_HANDLE;

    // The graph's passes.
    VkRenderPass shadow_pass = VK_NULL_HANDLE, depth_pass = VK_NULL_HANDLE, main_pass = VK_NULL_HANDLE,
                 post_pass = VK_NULL_HANDLE;

    // The scene's geometry, once, in the engine's buffers.
    io::Mesh sphere_mesh;
    Buffer positions, attributes, indices;
    MeshRange level_range, torus_range, sphere_range;
    render::EngineGeometry level_geometry, torus_geometry;

    // hemi: the material system (its default pass is the main pass, unused: the engine's shaders draw there),
    // the level and the PRT torus with their depth and shadow pipelines, the sky's parabolic maps.
    std::unique_ptr<render::MaterialSystem> system;
    std::unique_ptr<render::LightmapModel> level;
    std::unique_ptr<render::PrtModel> torus;
    std::unique_ptr<render::EnvironmentLighting> sky;
    // The level's reflection probe's maps, which the glossy ball reflects (box-projected).
    std::unique_ptr<render::EnvironmentLighting> reflection;
    render::EnvironmentMaterial reflective;
    size_t level_depth = 0, level_shadow = 0, torus_depth = 0, torus_shadow = 0;
    render::EnvironmentMaterial glossy;
    glm::mat4 level_model, torus_model;
    math::BoundingSphere level_bounds;
    // The level's mixed sun (render::mixed_lights: the direction towards it, its irradiance and shadowmask
    // channel), lit by the engine at run time; none when the level's sun is baked.
    std::optional<render::DynamicLight> sun;
    glm::mat4 sun_view_projection{1.0f};

    // The engine's own descriptors and pipelines.
    VkDescriptorSetLayout frame_layout = VK_NULL_HANDLE, level_layout = VK_NULL_HANDLE,
                          prt_layout = VK_NULL_HANDLE, env_layout = VK_NULL_HANDLE,
                          post_layout = VK_NULL_HANDLE;
    VkDescriptorPool pool = VK_NULL_HANDLE;
    std::vector<VkDescriptorSet> level_sets; // per primitive of the level
    std::vector<VkDescriptorSet> torus_sets; // per primitive of the torus
    VkDescriptorSet env_set = VK_NULL_HANDLE;
    VkBufferView torus_coefficients = VK_NULL_HANDLE;
    // The level's light probes, written once (io::probe_texels) and read by the probe-lit objects' shader.
    Buffer probe_buffer;
    VkBufferView probe_view = VK_NULL_HANDLE;
    Program depth_program, shadow_program, level_basis, level_ssbump, prt_program, probe_program, env_program,
        post_program;
    VkSampler shadow_sampler = VK_NULL_HANDLE, post_sampler = VK_NULL_HANDLE;

    // Per frame in flight: the engine's command buffer, fence, uniform blocks and images, and hemi's view of
    // the frame (set 0 of hemi's depth and shadow pipelines): descriptor sets of hemi's frame layout that the
    // engine allocates from its own pool over its own buffer (the camera's and the light's
    // shared::FrameUniforms, then instance records, which no draw here reads).
    struct Slot
    {
        VkCommandBuffer cmd = VK_NULL_HANDLE;
        VkFence fence = VK_NULL_HANDLE;
        VkSemaphore acquired = VK_NULL_HANDLE;
        Buffer uniforms;  // EngineFrame, host-mapped
        Buffer hemi_view; // camera FrameUniforms at 0, the light's at view_stride, a record at 2 view_stride
        Image shadow, depth, hdr;
        VkFramebuffer shadow_fb = VK_NULL_HANDLE, depth_fb = VK_NULL_HANDLE, main_fb = VK_NULL_HANDLE;
        VkDescriptorSet frame_set = VK_NULL_HANDLE, post_set = VK_NULL_HANDLE;
        VkDescriptorSet camera_set = VK_NULL_HANDLE, light_set = VK_NULL_HANDLE; // hemi's frame layout
    };
    std::array<Slot, kFramesInFlight> slots;
    VkDeviceSize view_stride = 0;
    std::vector<VkSemaphore> rendered; // per swapchain image
    std::vector<VkFramebuffer> post_fbs;
    uint64_t generation = ~uint64_t(0);
    uint32_t frame_index = 0;
    Buffer screenshot_buffer;

    Impl(Context& c, Swapchain& s, const samples::EngineAssets& a)
        : ctx(c), swapchain(s), assets(a), device(external(c)), vk(c.device)
    {
        vkGetPhysicalDeviceMemoryProperties(c.physical_device, &memory.properties);
        VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
        pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        pool_info.queueFamilyIndex = c.queue_family;
        check(vkCreateCommandPool(vk, &pool_info, nullptr, &command_pool), "vkCreateCommandPool");
        for (Slot& slot : slots)
        {
            VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
            alloc.commandPool = command_pool;
            alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
            alloc.commandBufferCount = 1;
            check(vkAllocateCommandBuffers(vk, &alloc, &slot.cmd), "vkAllocateCommandBuffers");
            VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
            fence.flags = VK_FENCE_CREATE_SIGNALED_BIT;
            check(vkCreateFence(vk, &fence, nullptr, &slot.fence), "vkCreateFence");
            VkSemaphoreCreateInfo sem{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
            check(vkCreateSemaphore(vk, &sem, nullptr, &slot.acquired), "vkCreateSemaphore");
        }
        create_passes();
        load_scene();
        create_descriptors();
        create_pipelines();
    }

    ~Impl()
    {
        vkDeviceWaitIdle(vk);
        destroy_sized();
        for (Slot& slot : slots)
        {
            vkDestroyFramebuffer(vk, slot.shadow_fb, nullptr);
            vkDestroyFence(vk, slot.fence, nullptr);
            vkDestroySemaphore(vk, slot.acquired, nullptr);
            destroy(vk, slot.uniforms);
            destroy(vk, slot.hemi_view);
            destroy(vk, slot.shadow);
        }
        vkDestroyCommandPool(vk, command_pool, nullptr);
        for (Program* p : {&depth_program, &shadow_program, &level_basis, &level_ssbump, &prt_program,
                           &probe_program, &env_program, &post_program})
        {
            vkDestroyPipeline(vk, p->pipeline, nullptr);
            vkDestroyPipelineLayout(vk, p->layout, nullptr);
        }
        vkDestroyDescriptorPool(vk, pool, nullptr);
        for (VkDescriptorSetLayout l : {frame_layout, level_layout, prt_layout, env_layout, post_layout})
            vkDestroyDescriptorSetLayout(vk, l, nullptr);
        vkDestroySampler(vk, shadow_sampler, nullptr);
        vkDestroySampler(vk, post_sampler, nullptr);
        vkDestroyBufferView(vk, torus_coefficients, nullptr);
        vkDestroyBufferView(vk, probe_view, nullptr);
        destroy(vk, probe_buffer);
        destroy(vk, screenshot_buffer);
        for (VkRenderPass p : {shadow_pass, depth_pass, main_pass, post_pass})
            vkDestroyRenderPass(vk, p, nullptr);
        // hemi's models go before the geometry they draw from.
        reflection.reset();
        sky.reset();
        torus.reset();
        level.reset();
        system.reset();
        destroy(vk, positions);
        destroy(vk, attributes);
        destroy(vk, indices);
    }

    static gpu::ExternalDevice external(const Context& c)
    {
        gpu::ExternalDevice e;
        e.instance = c.instance;
        e.physical_device = c.physical_device;
        e.device = c.device;
        e.queue = c.queue;
        e.queue_family = c.queue_family;
        e.independent_blend = c.independent_blend;
        e.debug_utils = c.debug_utils; // hemi names its objects: RenderDoc and the layer's messages show them
        e.get_instance_proc_addr = vkGetInstanceProcAddr; // volk's: hemi runs on the engine's entry points
        e.log = [](gpu::LogLevel level, bool, std::string_view message)
        {
            if (level >= gpu::LogLevel::Warning)
                std::fprintf(stderr, "hemi: %.*s\n", int(message.size()), message.data());
        };
        return e;
    }

    void create_passes()
    {
        // Shadow map: written, then read by the main pass's fragment shaders of the same frame.
        VkSubpassDependency shadow_out{0,
                                       VK_SUBPASS_EXTERNAL,
                                       VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                                       VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                                       VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                                       VK_ACCESS_SHADER_READ_BIT,
                                       0};
        const AttachmentSpec shadow_depth{kDepthFormat, VK_ATTACHMENT_LOAD_OP_CLEAR,
                                          VK_IMAGE_LAYOUT_UNDEFINED,
                                          VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL};
        shadow_pass = make_render_pass(vk, {}, &shadow_depth, {shadow_out});
        // Depth prepass: written, then tested by the main pass.
        VkSubpassDependency depth_out{0,
                                      VK_SUBPASS_EXTERNAL,
                                      VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                                      VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                          VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                                      VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                                      VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT,
                                      0};
        const AttachmentSpec prepass_depth{kDepthFormat, VK_ATTACHMENT_LOAD_OP_CLEAR,
                                           VK_IMAGE_LAYOUT_UNDEFINED,
                                           VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        depth_pass = make_render_pass(vk, {}, &prepass_depth, {depth_out});
        // Main pass: HDR colour (cleared) over the prepass's depth; read by the post pass.
        // (The HDR image's layout change is ordered before its clear by the same dependency.)
        VkSubpassDependency main_in{
            VK_SUBPASS_EXTERNAL,
            0,
            VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
            VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT |
                VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
            0};
        VkSubpassDependency main_out{0,
                                     VK_SUBPASS_EXTERNAL,
                                     VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                                     VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
                                     VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                                     VK_ACCESS_SHADER_READ_BIT,
                                     0};
        const AttachmentSpec hdr{kHdrFormat, VK_ATTACHMENT_LOAD_OP_CLEAR, VK_IMAGE_LAYOUT_UNDEFINED,
                                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
        const AttachmentSpec main_depth{kDepthFormat, VK_ATTACHMENT_LOAD_OP_LOAD,
                                        VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
                                        VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
        main_pass = make_render_pass(vk, {hdr}, &main_depth, {main_in, main_out});
        // Post pass into the swapchain image: its layout change waits for the acquire semaphore's stage.
        VkSubpassDependency post_in{VK_SUBPASS_EXTERNAL,
                                    0,
                                    VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                                    VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                                    0,
                                    VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                                    0};
        const AttachmentSpec present{swapchain.format, VK_ATTACHMENT_LOAD_OP_DONT_CARE,
                                     VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};
        post_pass = make_render_pass(vk, {present}, nullptr, {post_in});
    }

    // The scene's meshes into the engine's two vertex streams and index buffer, one after another.
    void load_geometry()
    {
        sphere_mesh = io::make_uv_sphere(1.0f, 48, 24);
        const io::Mesh* meshes[3] = {&assets.level.mesh, &assets.torus.mesh, &sphere_mesh};
        MeshRange* ranges[3] = {&level_range, &torus_range, &sphere_range};
        std::vector<glm::vec3> p;
        std::vector<VertexRest> rest;
        std::vector<uint32_t> idx;
        for (int i = 0; i < 3; ++i)
        {
            const io::Mesh& m = *meshes[i];
            *ranges[i] = {uint32_t(p.size()), uint32_t(idx.size()), uint32_t(m.indices.size())};
            for (size_t v = 0; v < m.positions.size(); ++v)
            {
                p.push_back(m.positions[v]);
                rest.push_back({v < m.normals.size() ? m.normals[v] : glm::vec3(0.0f, 0.0f, 1.0f),
                                v < m.tangents.size() ? m.tangents[v] : glm::vec4(1.0f, 0.0f, 0.0f, 1.0f),
                                v < m.uvs.size() ? m.uvs[v] : glm::vec2(0.0f),
                                v < m.uvs1.size() ? m.uvs1[v] : glm::vec2(0.0f)});
            }
            idx.insert(idx.end(), m.indices.begin(), m.indices.end());
        }
        auto upload = [&](Buffer& b, const void* data, size_t bytes, VkBufferUsageFlags usage)
        {
            b = create_buffer(vk, memory, bytes, usage);
            std::memcpy(b.mapped, data, bytes);
        };
        upload(positions, p.data(), p.size() * sizeof(glm::vec3), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
        upload(attributes, rest.data(), rest.size() * sizeof(VertexRest), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
        upload(indices, idx.data(), idx.size() * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT);
        auto geometry_of = [&](const MeshRange& r, const std::vector<io::Primitive>& primitives)
        {
            render::EngineGeometry g;
            g.layout = engine_layout();
            g.buffers.streams = 2;
            g.buffers.vertex_buffers[0] = positions.buffer;
            g.buffers.vertex_buffers[1] = attributes.buffer;
            g.buffers.index_buffer = indices.buffer;
            g.buffers.index_type = VK_INDEX_TYPE_UINT32;
            for (const io::Primitive& prim : primitives)
                g.primitives.push_back(
                    {r.first_index + prim.first_index, prim.index_count, int32_t(r.base_vertex)});
            if (primitives.empty())
                g.primitives.push_back({r.first_index, r.index_count, int32_t(r.base_vertex)});
            return g;
        };
        level_geometry = geometry_of(level_range, assets.level.primitives);
        torus_geometry = geometry_of(torus_range, assets.torus.primitives);
    }

    // Both streams (the main pass), or positions alone (the depth-only passes' own pipelines).
    void bind_geometry(VkCommandBuffer cmd, bool positions_only) const
    {
        const VkBuffer buffers[2] = {positions.buffer, attributes.buffer};
        const VkDeviceSize offsets[2] = {0, 0};
        vkCmdBindVertexBuffers(cmd, 0, positions_only ? 1 : 2, buffers, offsets);
        vkCmdBindIndexBuffer(cmd, indices.buffer, 0, VK_INDEX_TYPE_UINT32);
    }

    // A one-time command buffer of the engine's, submitted and waited for (loading).
    template <typename Record> void submit_once(Record&& record)
    {
        VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        alloc.commandPool = command_pool;
        alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        alloc.commandBufferCount = 1;
        VkCommandBuffer cmd;
        check(vkAllocateCommandBuffers(vk, &alloc, &cmd), "vkAllocateCommandBuffers");
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");
        record(cmd);
        check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
        VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &cmd;
        check(vkQueueSubmit(ctx.queue, 1, &submit, VK_NULL_HANDLE), "vkQueueSubmit");
        check(vkQueueWaitIdle(ctx.queue), "vkQueueWaitIdle");
        vkFreeCommandBuffers(vk, command_pool, 1, &cmd);
    }

    void load_scene()
    {
        load_geometry();
        // No default target: the engine draws colour with its own shaders, so hemi compiles only the depth
        // and shadow pipelines its models are given below.
        system = std::make_unique<render::MaterialSystem>(device);
        gpu::UploadBatch upload(device);
        level_model = math::gltf_to_world();
        level_bounds = math::bounding_sphere(assets.level.mesh, level_model);
        // The level's default technique is H4; its SSBump wall asks for "ssbump" itself (its material).
        level = std::make_unique<render::LightmapModel>(
            *system, assets.level, std::vector<std::string>{"h4", "h6"}, upload,
            std::map<std::string, std::string>{}, &level_geometry);
        render::PassDesc depth;
        depth.kind = render::PassKind::Depth;
        depth.target.render_pass = depth_pass;
        depth.target.color_attachments = 0;
        render::PassDesc shadow = depth;
        shadow.kind = render::PassKind::Shadow;
        shadow.target.render_pass = shadow_pass;
        level_depth = level->add_pass(depth);
        level_shadow = level->add_pass(shadow);
        for (const render::DynamicLight& l : render::mixed_lights(assets.level, level_model))
            if (!l.point)
            {
                sun = l;
                break;
            }
        if (sun)
            sun_view_projection = sun_matrix(sun->position, level_bounds);

        // The torus relit every frame: one lighting and one set of coefficients per frame in flight.
        render::PrtModelDesc prt;
        prt.technique = "h4";
        prt.frames_in_flight = kFramesInFlight;
        prt.geometry = &torus_geometry;
        torus = std::make_unique<render::PrtModel>(*system, assets.torus, prt, upload);
        torus_depth = torus->add_pass(depth);
        torus_shadow = torus->add_pass(shadow);
        // The torus on the floor, 1.3 units across, between the pillars.
        const math::BoundingSphere tb = math::bounding_sphere(assets.torus.mesh, math::gltf_to_world());
        const float scale = 0.65f / tb.radius;
        torus_model = glm::translate(glm::mat4(1.0f), glm::vec3(0.6f, -0.9f, 0.0f) - scale * tb.centre +
                                                          glm::vec3(0.0f, 0.0f, 0.65f)) *
                      glm::scale(glm::mat4(1.0f), glm::vec3(scale)) * math::gltf_to_world();

        glossy.kd = 0.25f;
        glossy.ks = 0.9f;
        sky = std::make_unique<render::EnvironmentLighting>(
            *system, assets.sky, std::span<const math::BrdfTable>{}, glossy, upload);
        if (assets.level.reflections.empty())
            throw std::runtime_error("the level has no reflection probe for the glossy ball");
        reflective = glossy;
        reflective.world_to_env =
            glm::mat3(glm::inverse(level_model)); // the probe's maps are in the level's frame
        reflection = std::make_unique<render::EnvironmentLighting>(*system, assets.level.reflections[0].maps,
                                                                   std::span<const math::BrdfTable>{},
                                                                   reflective, upload);
        // hemi's uploads, recorded into the engine's command buffer and submitted by the engine.
        submit_once([&](VkCommandBuffer cmd) { upload.record(cmd); });
        // The engine's own texel-buffer view of the coefficients hemi's transfer writes (every frame slot's).
        const gpu::BufferRange range = torus->coefficients().coefficients();
        VkBufferViewCreateInfo view{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
        view.buffer = range.buffer;
        view.format = VK_FORMAT_R32G32B32A32_SFLOAT;
        view.offset = range.offset;
        view.range = range.size;
        check(vkCreateBufferView(vk, &view, nullptr, &torus_coefficients), "vkCreateBufferView");
        // The level's probes for hemi_probe_irradiance: one RGBA32F texel buffer in hemi's layout.
        const std::vector<glm::vec4> probe_texels = io::probe_texels(assets.level.probes);
        if (probe_texels.empty())
            throw std::runtime_error("the level has no light probes for its dynamic objects");
        if (probe_texels.size() > device.limits().maxTexelBufferElements)
            throw std::runtime_error("the level's " + std::to_string(probe_texels.size()) +
                                     " probe texels exceed the device's texel buffers");
        probe_buffer = create_buffer(vk, memory, probe_texels.size() * sizeof(glm::vec4),
                                     VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT);
        std::memcpy(probe_buffer.mapped, probe_texels.data(), probe_texels.size() * sizeof(glm::vec4));
        view.buffer = probe_buffer.buffer;
        view.offset = 0;
        view.range = probe_texels.size() * sizeof(glm::vec4);
        check(vkCreateBufferView(vk, &view, nullptr, &probe_view), "vkCreateBufferView");
    }

    void create_descriptors()
    {
        const VkShaderStageFlags fs = VK_SHADER_STAGE_FRAGMENT_BIT, vs = VK_SHADER_STAGE_VERTEX_BIT;
        const VkDescriptorType image = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        auto binding = [](uint32_t b, VkDescriptorType type, VkShaderStageFlags stages) {
            return VkDescriptorSetLayoutBinding{b, type, 1, stages, nullptr};
        };
        const VkDescriptorSetLayoutBinding frame_bindings[] = {
            binding(0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, vs | fs), binding(1, image, fs),
            binding(2, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, fs)};
        const VkDescriptorSetLayoutBinding level_bindings[] = {
            binding(0, image, fs), binding(1, image, fs),  binding(2, image, fs),
            binding(3, image, fs), binding(5, image, fs),  binding(8, image, fs),
            binding(9, image, fs), binding(10, image, fs), binding(11, image, fs)};
        const VkDescriptorSetLayoutBinding prt_bindings[] = {
            binding(0, image, fs), binding(1, image, fs),
            binding(4, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, vs)};
        const VkDescriptorSetLayoutBinding env_bindings[] = {binding(6, image, fs), binding(7, image, fs)};
        const VkDescriptorSetLayoutBinding post_bindings[] = {binding(0, image, fs)};
        frame_layout = create_set_layout(vk, frame_bindings);
        level_layout = create_set_layout(vk, level_bindings);
        prt_layout = create_set_layout(vk, prt_bindings);
        env_layout = create_set_layout(vk, env_bindings);
        post_layout = create_set_layout(vk, post_bindings);
        const VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 8},
                                              {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 4},
                                              {image, 160},
                                              {VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, 8}};
        VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pool_info.maxSets = 40;
        pool_info.poolSizeCount = uint32_t(std::size(sizes));
        pool_info.pPoolSizes = sizes;
        check(vkCreateDescriptorPool(vk, &pool_info, nullptr, &pool), "vkCreateDescriptorPool");
        auto allocate = [&](VkDescriptorSetLayout layout)
        {
            VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
            info.descriptorPool = pool;
            info.descriptorSetCount = 1;
            info.pSetLayouts = &layout;
            VkDescriptorSet set;
            check(vkAllocateDescriptorSets(vk, &info, &set), "vkAllocateDescriptorSets");
            return set;
        };

        // The level: each primitive's material textures and the lightmaps hemi uploaded.
        const render::SceneSurfaces& surfaces = level->surfaces();
        const render::TextureSet& textures = surfaces.textures();
        const render::TexelCoefficients &h6 = level->coefficients("h6"), &h4 = level->coefficients("h4"),
                                        &rnm = level->coefficients("ssbump");
        for (size_t p = 0; p < surfaces.primitive_count(); ++p)
        {
            const io::Material& m = surfaces.material(p);
            const VkDescriptorSet set = allocate(level_layout);
            write_image(vk, set, 0, textures.sampler(m.base_color.sampler),
                        textures.image(m.base_color.image, true).view());
            write_image(vk, set, 1, textures.sampler(m.normal.sampler),
                        textures.image(m.normal.image, false).view());
            write_image(vk, set, 2, h6.sampler(), h6.pages().view());
            write_image(vk, set, 3, h4.sampler(), h4.pages().view());
            write_image(vk, set, 5, rnm.sampler(), rnm.pages().view());
            write_image(vk, set, 8, h6.table_sampler(), h6.page_table().view());
            write_image(vk, set, 9, h4.table_sampler(), h4.page_table().view());
            write_image(vk, set, 10, rnm.table_sampler(), rnm.page_table().view());
            write_image(vk, set, 11, h4.sampler(), h4.shadowmask().view());
            level_sets.push_back(set);
        }
        // The torus: its textures and the coefficients hemi's transfer pass writes.
        const render::SceneSurfaces& ts = torus->surfaces();
        for (size_t p = 0; p < ts.primitive_count(); ++p)
        {
            const io::Material& m = ts.material(p);
            const VkDescriptorSet set = allocate(prt_layout);
            write_image(vk, set, 0, ts.textures().sampler(m.base_color.sampler),
                        ts.textures().image(m.base_color.image, true).view());
            write_image(vk, set, 1, ts.textures().sampler(m.normal.sampler),
                        ts.textures().image(m.normal.image, false).view());
            write_texel_buffer(vk, set, 4, torus_coefficients);
            torus_sets.push_back(set);
        }
        env_set = allocate(env_layout);
        write_image(vk, env_set, 6, reflection->sampler(), reflection->glossy_map().view());
        write_image(vk, env_set, 7, reflection->sampler(), reflection->diffuse_map().view());

        // The shadow map is read with depth comparison (hardware PCF); the post pass reads the HDR image.
        VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
        s.magFilter = s.minFilter = VK_FILTER_LINEAR;
        s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        s.compareEnable = VK_TRUE;
        s.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
        s.maxLod = 0.0f;
        check(vkCreateSampler(vk, &s, nullptr, &shadow_sampler), "vkCreateSampler");
        s.magFilter = s.minFilter = VK_FILTER_NEAREST;
        s.compareEnable = VK_FALSE;
        check(vkCreateSampler(vk, &s, nullptr, &post_sampler), "vkCreateSampler");

        const VkPhysicalDeviceLimits& limits = device.limits();
        view_stride = (sizeof(shared::FrameUniforms) + limits.minUniformBufferOffsetAlignment - 1) /
                      limits.minUniformBufferOffsetAlignment * limits.minUniformBufferOffsetAlignment;
        view_stride = (view_stride + limits.minStorageBufferOffsetAlignment - 1) /
                      limits.minStorageBufferOffsetAlignment * limits.minStorageBufferOffsetAlignment;
        for (Slot& slot : slots)
        {
            slot.uniforms =
                create_buffer(vk, memory, sizeof(EngineFrame), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
            slot.shadow =
                create_image(vk, memory, {kShadowSize, kShadowSize}, kDepthFormat,
                             VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT);
            slot.shadow_fb =
                make_framebuffer(vk, shadow_pass, {slot.shadow.view}, {kShadowSize, kShadowSize});
            slot.frame_set = allocate(frame_layout);
            const VkDescriptorBufferInfo ubo{slot.uniforms.buffer, 0, VK_WHOLE_SIZE};
            VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
            w.dstSet = slot.frame_set;
            w.dstBinding = 0;
            w.descriptorCount = 1;
            w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
            w.pBufferInfo = &ubo;
            vkUpdateDescriptorSets(vk, 1, &w, 0, nullptr);
            write_image(vk, slot.frame_set, 1, shadow_sampler, slot.shadow.view,
                        VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL);
            write_texel_buffer(vk, slot.frame_set, 2, probe_view);
            slot.post_set = allocate(post_layout);

            // hemi's view of this slot: two sets of hemi's frame layout over the engine's buffer.
            slot.hemi_view =
                create_buffer(vk, memory, 2 * view_stride + sizeof(shared::DrawPush),
                              VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
            std::memset(slot.hemi_view.mapped, 0, slot.hemi_view.size);
            slot.camera_set = allocate(system->frame_layout());
            slot.light_set = allocate(system->frame_layout());
            const VkDescriptorBufferInfo infos[3] = {
                {slot.hemi_view.buffer, 0, sizeof(shared::FrameUniforms)},
                {slot.hemi_view.buffer, view_stride, sizeof(shared::FrameUniforms)},
                {slot.hemi_view.buffer, 2 * view_stride, sizeof(shared::DrawPush)}};
            VkWriteDescriptorSet writes[4]{};
            for (int i = 0; i < 4; ++i)
            {
                const bool uniforms = i % 2 == 0;
                writes[i].sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET;
                writes[i].dstSet = i < 2 ? slot.camera_set : slot.light_set;
                writes[i].dstBinding = uniforms ? HEMI_FRAME_BINDING_UNIFORMS : HEMI_FRAME_BINDING_INSTANCES;
                writes[i].descriptorCount = 1;
                writes[i].descriptorType =
                    uniforms ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
                writes[i].pBufferInfo = uniforms ? &infos[i / 2] : &infos[2];
            }
            vkUpdateDescriptorSets(vk, 4, writes, 0, nullptr);
        }
    }

    void create_pipelines()
    {
        const render::VertexLayout layout = engine_layout();
        const std::vector<VkVertexInputBindingDescription> bindings = {
            {0, layout.strides[0], VK_VERTEX_INPUT_RATE_VERTEX},
            {1, layout.strides[1], VK_VERTEX_INPUT_RATE_VERTEX}};
        const std::vector<VkVertexInputAttributeDescription> attributes_in = {
            {0, 0, layout.position.format, layout.position.offset},
            {1, 1, layout.normal.format, layout.normal.offset},
            {2, 1, layout.tangent.format, layout.tangent.offset},
            {3, 1, layout.uv0.format, layout.uv0.offset},
            {4, 1, layout.uv1.format, layout.uv1.offset}};
        auto program = [&](std::vector<VkDescriptorSetLayout> sets, uint32_t push, PipelineDesc d)
        {
            Program p;
            p.layout = create_pipeline_layout(vk, sets, push);
            d.layout = p.layout;
            p.pipeline = create_pipeline(vk, d);
            return p;
        };

        // Depth-only: positions alone (stream 0).
        PipelineDesc d;
        d.bindings = {bindings[0]};
        d.attributes = {attributes_in[0]};
        d.color_attachments = 0;
        d.render_pass = depth_pass;
        d.vertex_shader = spirv("depth.vert");
        depth_program = program({frame_layout}, sizeof(EngineObject), d);
        d.render_pass = shadow_pass;
        d.vertex_shader = spirv("depth_shadow.vert");
        d.depth_bias_constant = 1.25f;
        d.depth_bias_slope = 1.75f;
        shadow_program = program({frame_layout}, sizeof(EngineObject), d);

        PipelineDesc m;
        m.bindings = bindings;
        m.attributes = attributes_in;
        m.render_pass = main_pass;
        m.depth_write = false;
        m.depth_compare = VK_COMPARE_OP_LESS_OR_EQUAL; // against the prepass: each pixel shaded once
        m.vertex_shader = spirv("main.vert");
        m.fragment_shader = spirv("main_level.frag");
        m.specialization = {0, 4, 0};
        level_basis = program({frame_layout, level_layout}, sizeof(EngineObject), m);
        m.specialization = {1, 4, 0};
        level_ssbump = program({frame_layout, level_layout}, sizeof(EngineObject), m);
        const uint32_t k = uint32_t(torus->basis().size);
        m.vertex_shader = spirv("main_prt.vert");
        m.fragment_shader = spirv("main_prt.frag");
        m.specialization = {0, k, uint32_t(torus->basis().id)};
        prt_program = program({frame_layout, prt_layout}, sizeof(EngineObject), m);
        m.vertex_shader = spirv("main.vert");
        m.fragment_shader = spirv("main_probe.frag");
        m.specialization = {0, 4, 0};
        probe_program = program({frame_layout}, sizeof(EngineObject), m);
        m.fragment_shader = spirv("main_env.frag");
        env_program = program({frame_layout, env_layout}, sizeof(EngineObject), m);

        PipelineDesc p;
        p.vertex_shader = spirv("post.vert");
        p.fragment_shader = spirv("post.frag");
        p.render_pass = post_pass;
        p.depth_test = false;
        p.depth_write = false;
        p.cull = VK_CULL_MODE_NONE;
        post_program = program({post_layout}, sizeof(PostPush), p);
    }

    // What depends on the swapchain's size: depth and HDR images, their framebuffers, the post targets.
    void destroy_sized()
    {
        for (Slot& slot : slots)
        {
            for (VkFramebuffer* fb : {&slot.depth_fb, &slot.main_fb})
                if (*fb)
                {
                    vkDestroyFramebuffer(vk, *fb, nullptr);
                    *fb = VK_NULL_HANDLE;
                }
            destroy(vk, slot.depth);
            destroy(vk, slot.hdr);
        }
        for (VkFramebuffer fb : post_fbs)
            vkDestroyFramebuffer(vk, fb, nullptr);
        post_fbs.clear();
        for (VkSemaphore s : rendered)
            vkDestroySemaphore(vk, s, nullptr);
        rendered.clear();
    }

    void create_sized()
    {
        const VkExtent2D e = swapchain.extent;
        for (Slot& slot : slots)
        {
            slot.depth =
                create_image(vk, memory, e, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT);
            slot.hdr = create_image(vk, memory, e, kHdrFormat,
                                    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT);
            slot.depth_fb = make_framebuffer(vk, depth_pass, {slot.depth.view}, e);
            slot.main_fb = make_framebuffer(vk, main_pass, {slot.hdr.view, slot.depth.view}, e);
            write_image(vk, slot.post_set, 0, post_sampler, slot.hdr.view);
        }
        for (VkImageView v : swapchain.views)
        {
            post_fbs.push_back(make_framebuffer(vk, post_pass, {v}, e));
            VkSemaphoreCreateInfo sem{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
            VkSemaphore s;
            check(vkCreateSemaphore(vk, &sem, nullptr, &s), "vkCreateSemaphore");
            rendered.push_back(s);
        }
        generation = swapchain.generation;
    }

    void resize()
    {
        vkDeviceWaitIdle(vk);
        destroy_sized();
        swapchain.recreate();
        create_sized();
    }

    // The probe-lit spheres circle the room's centre at three heights, the lowest starting in the sun's beam
    // through the wide opening (its shadow on the sunlit floor).
    glm::vec3 sphere_position(uint32_t i, float t) const
    {
        const float a = 0.35f * t + 2.0944f * float(i) + 3.1416f;
        return glm::vec3(1.9f * std::cos(a), 1.9f * std::sin(a), 0.45f + 0.5f * float(i));
    }

    FrameStats record(Slot& slot, uint32_t slot_index, uint32_t image, const Settings& settings,
                      const FrameState& state, bool screenshot)
    {
        const VkCommandBuffer cmd = slot.cmd;
        const VkExtent2D e = swapchain.extent;
        const float aspect = float(e.width) / float(e.height);
        FrameStats stats;

        // The frame's data, into this slot's mapped block (the slot's fence has passed: no frame reads it).
        EngineFrame f{};
        const glm::vec3 eye = settings.camera.eye;
        f.view_projection = math::camera_matrix(settings.camera, level_bounds, aspect);
        f.eye = glm::vec4(eye, settings.lod_distance);
        // The mixed sun: lit at run time (by the shadowmask alone in --baked-only, as hemi-render lights it),
        // its shadow map drawn within the shadow distance.
        const bool sun_on = sun.has_value();
        const bool shadow_map =
            sun_on && settings.shadow_map && settings.shadow_distance > 0.0f && !settings.baked_only;
        f.sun_view_projection = sun_view_projection;
        f.sun_direction = glm::vec4(sun ? sun->position : glm::vec3(0.0f, 0.0f, 1.0f), sun_on ? 1.0f : 0.0f);
        f.sun_irradiance =
            glm::vec4(sun ? sun->irradiance : glm::vec3(0.0f), sun ? float(sun->shadowmask_channel) : -1.0f);
        f.shadow = glm::vec4(settings.shadow_distance, kShadowFade, shadow_map ? 1.0f : 0.0f, 0.0f);
        f.fog = glm::vec4(0.05f, 0.06f, 0.08f, settings.baked_only ? 0.0f : settings.fog);
        f.mode = glm::ivec4(settings.baked_only ? 2 : settings.basis,
                            settings.specular_only && !settings.baked_only ? 2
                            : settings.lighting_only                       ? 1
                                                                           : 0,
                            settings.coat && !settings.baked_only ? 1 : 0, 0);
        const bool objects = settings.objects && !settings.baked_only;
        // The level's probes, which the spheres look up per pixel; at the glossy ball and the torus, their
        // occlusion of the mixed sun (its channel), the objects' static shadow beyond the shadow distance.
        f.world_to_level = glm::inverse(level_model);
        std::array<float, kSpheres + 2> occlusion;
        occlusion.fill(1.0f);
        for (uint32_t s = 0; s <= kSpheres + 1; ++s)
        {
            const glm::vec3 at =
                s <= kSpheres ? glm::vec3(object_model(s, state)[3]) : glm::vec3(torus_model[3]);
            std::array<glm::vec3, 9> sh;
            std::array<float, 4> occluded;
            if (!render::probe_lighting(assets.level, at, level_model, sh, &occluded))
                throw std::runtime_error("the level has no light probes for its dynamic objects");
            if (sun && sun->shadowmask_channel >= 0)
                occlusion[s] = occluded[size_t(sun->shadowmask_channel)];
            if (s < kSpheres)
            {
                // Where the sphere is on screen (its centre, and its radius along the camera's right), and
                // what the probes give it at its centre.
                SphereSeen& seen = stats.spheres[s];
                const glm::vec3 forward = glm::normalize(settings.camera.target - eye);
                const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0.0f, 0.0f, 1.0f)));
                auto pixel = [&](const glm::vec3& p)
                {
                    const glm::vec4 c = f.view_projection * glm::vec4(p, 1.0f);
                    return glm::vec2((c.x / c.w * 0.5f + 0.5f) * float(e.width),
                                     (c.y / c.w * 0.5f + 0.5f) * float(e.height));
                };
                seen.in_front = glm::dot(at - eye, forward) > 0.5f;
                seen.centre = pixel(at);
                seen.radius = glm::distance(pixel(at + 0.32f * right), seen.centre);
                seen.light = float(math::luminance(glm::dvec3(sh[0])));
                seen.sun_share = occlusion[s];
            }
        }
        const float env_degrees = 25.0f * state.env_time;
        glossy.world_to_env =
            glm::mat3(glm::rotate(glm::mat4(1.0f), glm::radians(-env_degrees), glm::vec3(0.0f, 0.0f, 1.0f)));
        // The glossy ball reflects the level's reflection probe, box-projected in the level's frame.
        f.env = reflection->uniforms(reflective);
        const io::ReflectionProbe& probe = assets.level.reflections[0];
        f.reflection_centre = glm::vec4(probe.centre, 1.0f);
        f.reflection_min = glm::vec4(probe.box_min, 0.0f);
        f.reflection_max = glm::vec4(probe.box_max, 0.0f);
        std::memcpy(slot.uniforms.mapped, &f, sizeof f);
        // hemi's view of the frame, into the slot's own buffer (set 0 of hemi's depth and shadow pipelines).
        render::FrameData camera_frame;
        camera_frame.view_projection = f.view_projection;
        camera_frame.eye = eye;
        render::FrameData light_frame;
        light_frame.view_projection = sun_view_projection;
        light_frame.eye = level_bounds.centre + 2.0f * level_bounds.radius * glm::vec3(f.sun_direction);
        shared::FrameUniforms hemi_uniforms;
        if (!render::frame_uniforms(*system, camera_frame, hemi_uniforms))
            throw std::runtime_error("hemi refused the camera's frame data");
        std::memcpy(slot.hemi_view.mapped, &hemi_uniforms, sizeof hemi_uniforms);
        if (!render::frame_uniforms(*system, light_frame, hemi_uniforms))
            throw std::runtime_error("hemi refused the light's frame data");
        std::memcpy(static_cast<std::byte*>(slot.hemi_view.mapped) + view_stride, &hemi_uniforms,
                    sizeof hemi_uniforms);

        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");

        // hemi's per-frame work, outside render passes: the torus relit by the turning sky into this slot's
        // coefficients. hemi records the dispatch and declares what it reads and writes; the engine places
        // the barrier between the transfer and the vertex shaders that read the coefficients (hemi's depth
        // and shadow pipelines, the engine's main_prt.vert). Earlier reads of the slot's coefficients are
        // done: the slot's fence has passed.
        if (objects)
        {
            render::PrtInstance instance;
            instance.model = torus_model;
            instance.world_lighting = assets.sky_sh;
            instance.rotate_degrees = env_degrees;
            render::AccessList transfer, reads;
            if (!torus->record_transfer(cmd, std::span<const render::PrtInstance>(&instance, 1), slot_index,
                                        transfer) ||
                !torus->draw_accesses(slot_index, reads))
                throw std::runtime_error("hemi refused the torus's transfer (see its message)");
            render::record_barrier(cmd, transfer.accesses(), reads.accesses());
        }

        const std::vector<render::LightmapDraw> list = level->draw_list("h4", 0);
        auto draw_objects_depth = [&](const Program& program, size_t torus_pass, VkDescriptorSet hemi_frame)
        {
            if (!objects)
                return;
            torus->draw(cmd, hemi_frame, 0, torus_model, torus_pass, slot_index);
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0, 1,
                                    &slot.frame_set, 0, nullptr);
            bind_geometry(cmd, true);
            for (uint32_t s = 0; s <= kSpheres; ++s)
            {
                EngineObject o;
                o.model = object_model(s, state);
                vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
                vkCmdDrawIndexed(cmd, sphere_range.index_count, 1, sphere_range.first_index,
                                 int32_t(sphere_range.base_vertex), 0);
            }
        };

        // 1. The shadow map from the sun.
        VkClearValue clear_depth{};
        clear_depth.depthStencil = {1.0f, 0};
        VkRenderPassBeginInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
        rp.renderPass = shadow_pass;
        rp.framebuffer = slot.shadow_fb;
        rp.renderArea = {{0, 0}, {kShadowSize, kShadowSize}};
        rp.clearValueCount = 1;
        rp.pClearValues = &clear_depth;
        vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
        set_viewport(cmd, {kShadowSize, kShadowSize});
        if (shadow_map)
        {
            level->draw(cmd, slot.light_set, "h4", level_model, level_shadow);
            draw_objects_depth(shadow_program, torus_shadow, slot.light_set);
        }
        vkCmdEndRenderPass(cmd);

        // 2. The depth prepass.
        rp.renderPass = depth_pass;
        rp.framebuffer = slot.depth_fb;
        rp.renderArea = {{0, 0}, e};
        vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
        set_viewport(cmd, e);
        std::vector<const render::LightmapDraw*> visible_entries;
        for (const render::LightmapDraw& entry : list)
            if (visible(f.view_projection, level_model, entry.bounds_min, entry.bounds_max))
                visible_entries.push_back(&entry);
            else
                ++stats.culled;
        for (const render::LightmapDraw* entry : visible_entries)
            level->draw(cmd, slot.camera_set, *entry, level_model, level_depth);
        draw_objects_depth(depth_program, torus_depth, slot.camera_set);
        vkCmdEndRenderPass(cmd);

        // 3. The main pass: the engine's own shaders over hemi's data.
        // Where no surface is (the openings), the sky's horizon colour (--baked-only: black, as hemi-render).
        VkClearValue clears[2]{};
        if (!settings.baked_only)
            clears[0].color = {{0.55f, 0.65f, 0.85f, 1.0f}};
        clears[1].depthStencil = {1.0f, 0};
        rp.renderPass = main_pass;
        rp.framebuffer = slot.main_fb;
        rp.clearValueCount = 2;
        rp.pClearValues = clears;
        vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
        set_viewport(cmd, e);
        bind_geometry(cmd, false);
        for (const render::LightmapDraw* entry : visible_entries)
        {
            const Program& program = *entry->technique == "ssbump" ? level_ssbump : level_basis;
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
            const VkDescriptorSet sets[2] = {slot.frame_set, level_sets[entry->primitive]};
            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0, 2, sets, 0,
                                    nullptr);
            EngineObject o;
            o.model = level_model;
            o.albedo = entry->material->base_color_factor;
            if (entry->material->name == "polished floor")
                o.material = glm::vec4(kFloorRoughness, kFloorF0, 1.0f, 0.0f);
            vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
            // The entry's indices are the engine's own (level_geometry's ranges).
            vkCmdDrawIndexed(cmd, entry->index_count, 1, entry->first_index, int32_t(level_range.base_vertex),
                             0);
            ++stats.draws;
        }
        if (objects)
        {
            // The torus, relit this frame.
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, prt_program.pipeline);
            const render::SceneSurfaces& ts = torus->surfaces();
            // This slot's coefficients of vertex v are at coefficient_offset + v K; gl_VertexIndex counts
            // the torus's base vertex in the engine's buffers, taken out here.
            const uint32_t coefficients =
                torus->instance_record(0, torus_model, slot_index).coefficient_offset -
                torus_range.base_vertex * uint32_t(torus->basis().size);
            for (size_t p = 0; p < ts.primitive_count(); ++p)
            {
                const VkDescriptorSet sets[2] = {slot.frame_set, torus_sets[p]};
                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, prt_program.layout, 0, 2, sets,
                                        0, nullptr);
                EngineObject o;
                o.model = torus_model;
                o.albedo = ts.material(p).base_color_factor;
                o.index.x = int32_t(coefficients);
                o.material.z = occlusion[kSpheres + 1];
                vkCmdPushConstants(cmd, prt_program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
                const render::SceneSurfaces::Primitive prim = ts.primitive(p);
                vkCmdDrawIndexed(cmd, prim.index_count, 1, prim.first_index, int32_t(torus_range.base_vertex),
                                 0);
            }
            // The spheres lit by the probes, then the glossy ball.
            const glm::vec4 colours[kSpheres] = {
                {0.9f, 0.3f, 0.25f, 1}, {0.9f, 0.85f, 0.8f, 1}, {0.3f, 0.5f, 0.9f, 1}};
            for (uint32_t s = 0; s <= kSpheres; ++s)
            {
                const Program& program = s < kSpheres ? probe_program : env_program;
                vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
                const VkDescriptorSet sets[2] = {slot.frame_set, env_set};
                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0,
                                        s < kSpheres ? 1 : 2, sets, 0, nullptr);
                EngineObject o;
                o.model = object_model(s, state);
                o.albedo = s < kSpheres ? colours[s] : glm::vec4(0.8f, 0.75f, 0.6f, 1.0f);
                o.index.x = int32_t(s);
                o.material.z = occlusion[s];
                vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
                vkCmdDrawIndexed(cmd, sphere_range.index_count, 1, sphere_range.first_index,
                                 int32_t(sphere_range.base_vertex), 0);
            }
        }
        vkCmdEndRenderPass(cmd);

        // 4. Post: exposure and tonemap into the swapchain image.
        VkClearValue none{};
        rp.renderPass = post_pass;
        rp.framebuffer = post_fbs[image];
        rp.clearValueCount = 1;
        rp.pClearValues = &none;
        vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
        set_viewport(cmd, e);
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, post_program.pipeline);
        vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, post_program.layout, 0, 1,
                                &slot.post_set, 0, nullptr);
        const PostPush post{settings.baked_only ? 1.0f : settings.exposure,
                            settings.tonemap && !settings.baked_only ? 1 : 0, swapchain.srgb ? 0 : 1};
        vkCmdPushConstants(cmd, post_program.layout, VK_SHADER_STAGE_ALL, 0, sizeof post, &post);
        vkCmdDraw(cmd, 3, 1, 0, 0);
        vkCmdEndRenderPass(cmd);

        if (screenshot)
            record_screenshot(cmd, swapchain.images[image]);
        check(vkEndCommandBuffer(cmd), "vkEndCommandBuffer");
        return stats;
    }

    // Sphere i < kSpheres: a probe-lit sphere; i == kSpheres: the glossy ball, standing still.
    glm::mat4 object_model(uint32_t i, const FrameState& state) const
    {
        if (i == kSpheres)
            return glm::translate(glm::mat4(1.0f), glm::vec3(1.6f, 1.0f, 0.5f)) *
                   glm::scale(glm::mat4(1.0f), glm::vec3(0.5f));
        return glm::translate(glm::mat4(1.0f), sphere_position(i, state.object_time)) *
               glm::scale(glm::mat4(1.0f), glm::vec3(0.32f));
    }

    void record_screenshot(VkCommandBuffer cmd, VkImage image)
    {
        const VkExtent2D e = swapchain.extent;
        destroy(vk, screenshot_buffer);
        screenshot_buffer = create_buffer(vk, memory, VkDeviceSize(e.width) * e.height * 4,
                                          VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
        VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
        b.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        b.oldLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
        b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        b.image = image;
        b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                             VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
        VkBufferImageCopy copy{};
        copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        copy.imageExtent = {e.width, e.height, 1};
        vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, screenshot_buffer.buffer, 1,
                               &copy);
        b.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
        b.dstAccessMask = 0;
        b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        b.newLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0,
                             nullptr, 0, nullptr, 1, &b);
        // The copy is made visible to the host when the frame's fence signals (a queue submission's
        // completion makes its writes available; the readback memory is coherent).
        VkMemoryBarrier host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &host, 0,
                             nullptr, 0, nullptr);
    }

    void write_screenshot(const std::filesystem::path& path)
    {
        const VkExtent2D e = swapchain.extent;
        io::ImageRgba8 img{e.width, e.height, std::vector<uint8_t>(size_t(e.width) * e.height * 4)};
        std::memcpy(img.pixels.data(), screenshot_buffer.mapped, img.pixels.size());
        const bool bgra =
            swapchain.format == VK_FORMAT_B8G8R8A8_SRGB || swapchain.format == VK_FORMAT_B8G8R8A8_UNORM;
        for (size_t i = 0; i < img.pixels.size(); i += 4)
        {
            if (bgra)
                std::swap(img.pixels[i], img.pixels[i + 2]);
            img.pixels[i + 3] = 255;
        }
        io::write_png(path, img);
        destroy(vk, screenshot_buffer);
    }

    FrameStats frame(const Settings& settings, const FrameState& state,
                     const std::filesystem::path& screenshot)
    {
        if (generation != swapchain.generation || post_fbs.empty())
        {
            vkDeviceWaitIdle(vk);
            destroy_sized();
            create_sized();
        }
        const uint32_t slot_index = frame_index % kFramesInFlight;
        Slot& slot = slots[slot_index];
        // The slot's previous frame (two frames ago) has finished: its command buffer, uniform block and
        // images are free.
        check(vkWaitForFences(vk, 1, &slot.fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
        uint32_t image = 0;
        VkResult r =
            vkAcquireNextImageKHR(vk, swapchain.handle, UINT64_MAX, slot.acquired, VK_NULL_HANDLE, &image);
        if (r == VK_ERROR_OUT_OF_DATE_KHR)
        {
            resize();
            return {};
        }
        if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR)
            check(r, "vkAcquireNextImageKHR");
        check(vkResetFences(vk, 1, &slot.fence), "vkResetFences");
        check(vkResetCommandBuffer(slot.cmd, 0), "vkResetCommandBuffer");
        const bool shot = !screenshot.empty();
        if (shot && !(swapchain_usage_has_transfer()))
            throw std::runtime_error(
                "the window's swapchain cannot be copied (no TRANSFER_SRC usage): no screenshot");
        const FrameStats stats = record(slot, slot_index, image, settings, state, shot);

        const VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
        VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        submit.waitSemaphoreCount = 1;
        submit.pWaitSemaphores = &slot.acquired;
        submit.pWaitDstStageMask = &wait_stage;
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &slot.cmd;
        submit.signalSemaphoreCount = 1;
        submit.pSignalSemaphores = &rendered[image];
        check(vkQueueSubmit(ctx.queue, 1, &submit, slot.fence), "vkQueueSubmit");
        VkPresentInfoKHR present{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
        present.waitSemaphoreCount = 1;
        present.pWaitSemaphores = &rendered[image];
        present.swapchainCount = 1;
        present.pSwapchains = &swapchain.handle;
        present.pImageIndices = &image;
        r = vkQueuePresentKHR(ctx.queue, &present);
        if (shot)
        {
            check(vkWaitForFences(vk, 1, &slot.fence, VK_TRUE, UINT64_MAX), "vkWaitForFences");
            write_screenshot(screenshot);
        }
        ++frame_index;
        if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR)
            resize();
        else if (r != VK_SUCCESS)
            check(r, "vkQueuePresentKHR");
        return stats;
    }

    bool swapchain_usage_has_transfer() const
    {
        VkSurfaceCapabilitiesKHR caps{};
        vkGetPhysicalDeviceSurfaceCapabilitiesKHR(ctx.physical_device, ctx.surface, &caps);
        return (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT) != 0;
    }
};

Renderer::Renderer(Context& context, Swapchain& swapchain, const samples::EngineAssets& assets)
    : impl_(std::make_unique<Impl>(context, swapchain, assets))
{
}

Renderer::~Renderer() = default;

FrameStats Renderer::frame(const Settings& settings, const FrameState& state,
                           const std::filesystem::path& screenshot)
{
    return impl_->frame(settings, state, screenshot);
}

void Renderer::finish()
{
    vkDeviceWaitIdle(impl_->vk);
}

} // namespace engine
