#include "renderer.h"

#include <hemi/gpu/handle.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/upload.h>
#include <hemi/io/image.h>
#include <hemi/math/camera.h>
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
#include <cstdio>
#include <cstring>
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

void check(VkResult r, const char* what)
{
    if (r != VK_SUCCESS)
        throw std::runtime_error(std::string(what) + " failed (VkResult " + std::to_string(int(r)) + ")");
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
    glm::mat4 light_view_projection;
    glm::vec4 eye, light_position, light_axis, light_intensity, fog;
    glm::ivec4 mode;
    glm::vec4 probe_sh[kSpheres * 9];
    shared::EnvironmentUniforms env;
};
struct EngineObject
{
    glm::mat4 model;
    glm::vec4 albedo{1.0f};
    glm::ivec4 index{0};
};
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

} // namespace

struct Renderer::Impl
{
    Context& ctx;
    Swapchain& swapchain;
    const samples::EngineAssets& assets;
    gpu::Device device;
    VkDevice vk;

    // The graph's passes.
    VkRenderPass shadow_pass = VK_NULL_HANDLE, depth_pass = VK_NULL_HANDLE, main_pass = VK_NULL_HANDLE,
                 post_pass = VK_NULL_HANDLE;

    // hemi: the material system (its default pass is the main pass, unused: the engine's shaders draw there),
    // the level and the PRT torus with their depth and shadow pipelines, the sky's parabolic maps.
    std::unique_ptr<render::MaterialSystem> system;
    std::unique_ptr<render::LightmapModel> level;
    std::unique_ptr<render::PrtModel> torus;
    std::unique_ptr<render::EnvironmentLighting> sky;
    std::unique_ptr<render::GpuMesh> sphere;
    io::Mesh sphere_mesh;
    size_t level_depth = 0, level_shadow = 0, torus_depth = 0, torus_shadow = 0;
    std::unique_ptr<render::FrameSet> camera_set, light_set; // set 0 of hemi's depth and shadow pipelines
    render::EnvironmentMaterial glossy;
    glm::mat4 level_model, torus_model;
    math::BoundingSphere level_bounds;

    // The engine's own descriptors and pipelines.
    gpu::DescriptorSetLayout frame_layout, level_layout, prt_layout, env_layout, post_layout;
    gpu::DescriptorPool pool;
    std::vector<VkDescriptorSet> level_sets; // per primitive of the level
    std::vector<VkDescriptorSet> torus_sets; // per primitive of the torus
    VkDescriptorSet env_set = VK_NULL_HANDLE;
    gpu::BufferView torus_coefficients;
    gpu::Program depth_program, shadow_program, level_basis, level_ssbump, prt_program, probe_program,
        env_program, post_program;
    gpu::Sampler shadow_sampler, post_sampler;

    struct Slot
    {
        VkCommandBuffer cmd = VK_NULL_HANDLE;
        VkFence fence = VK_NULL_HANDLE;
        VkSemaphore acquired = VK_NULL_HANDLE;
        gpu::Buffer uniforms; // EngineFrame, host-mapped
        gpu::Image shadow, depth, hdr;
        VkFramebuffer shadow_fb = VK_NULL_HANDLE, depth_fb = VK_NULL_HANDLE, main_fb = VK_NULL_HANDLE;
        VkDescriptorSet frame_set = VK_NULL_HANDLE, post_set = VK_NULL_HANDLE;
    };
    std::array<Slot, kFramesInFlight> slots;
    VkCommandPool command_pool = VK_NULL_HANDLE;
    std::vector<VkSemaphore> rendered; // per swapchain image
    std::vector<VkFramebuffer> post_fbs;
    uint64_t generation = ~uint64_t(0);
    uint32_t frame_index = 0;
    gpu::Buffer screenshot_buffer;

    Impl(Context& c, Swapchain& s, const samples::EngineAssets& a)
        : ctx(c), swapchain(s), assets(a), device(external(c)), vk(c.device)
    {
        create_passes();
        load_scene();
        create_descriptors();
        create_pipelines();
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
        }
        vkDestroyCommandPool(vk, command_pool, nullptr);
        for (VkRenderPass p : {shadow_pass, depth_pass, main_pass, post_pass})
            vkDestroyRenderPass(vk, p, nullptr);
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

    void load_scene()
    {
        render::RenderTargetDesc main_target;
        main_target.render_pass = main_pass;
        system = std::make_unique<render::MaterialSystem>(device, main_target);
        gpu::UploadBatch upload(device);
        level_model = math::gltf_to_world();
        level_bounds = math::bounding_sphere(assets.level.mesh, level_model);
        // The level's default technique is H4; its SSBump wall asks for "ssbump" itself (its material).
        level = std::make_unique<render::LightmapModel>(*system, assets.level,
                                                        std::vector<std::string>{"h4", "h6"}, upload);
        render::PassDesc depth;
        depth.kind = render::PassKind::Depth;
        depth.target.render_pass = depth_pass;
        depth.target.color_attachments = 0;
        render::PassDesc shadow = depth;
        shadow.kind = render::PassKind::Shadow;
        shadow.target.render_pass = shadow_pass;
        level_depth = level->add_pass(depth);
        level_shadow = level->add_pass(shadow);

        render::PrtModelDesc prt;
        prt.technique = "h4";
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
        sphere_mesh = io::make_uv_sphere(1.0f, 48, 24);
        sphere = std::make_unique<render::GpuMesh>(device, sphere_mesh, upload);
        upload.submit_and_wait();
        camera_set = std::make_unique<render::FrameSet>(*system);
        light_set = std::make_unique<render::FrameSet>(*system);
        const gpu::BufferRange range = torus->coefficients().coefficients();
        torus_coefficients = gpu::create_buffer_view(device, range.buffer, VK_FORMAT_R32G32B32A32_SFLOAT,
                                                     range.offset, range.size);
    }

    void create_descriptors()
    {
        const VkShaderStageFlags fs = VK_SHADER_STAGE_FRAGMENT_BIT, vs = VK_SHADER_STAGE_VERTEX_BIT;
        const VkDescriptorType image = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
        const std::vector<gpu::Binding> frame_bindings = {{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, vs | fs},
                                                          {1, image, fs}};
        const std::vector<gpu::Binding> level_bindings = {{0, image, fs}, {1, image, fs}, {2, image, fs},
                                                          {3, image, fs}, {5, image, fs}, {8, image, fs},
                                                          {9, image, fs}, {10, image, fs}};
        const std::vector<gpu::Binding> prt_bindings = {
            {0, image, fs}, {1, image, fs}, {4, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, vs}};
        const std::vector<gpu::Binding> env_bindings = {{6, image, fs}, {7, image, fs}};
        const std::vector<gpu::Binding> post_bindings = {{0, image, fs}};
        frame_layout = gpu::create_set_layout(device, frame_bindings);
        level_layout = gpu::create_set_layout(device, level_bindings);
        prt_layout = gpu::create_set_layout(device, prt_bindings);
        env_layout = gpu::create_set_layout(device, env_bindings);
        post_layout = gpu::create_set_layout(device, post_bindings);
        std::vector<gpu::Binding> all = {{0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, vs | fs, 4},
                                         {0, image, fs, 160},
                                         {0, VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER, vs, 4}};
        pool = gpu::create_descriptor_pool(device, all, 32);

        auto image_write = [](uint32_t binding, VkSampler sampler, VkImageView view,
                              VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)
        {
            gpu::DescriptorWrite w;
            w.binding = binding;
            w.type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
            w.image = {sampler, view, layout};
            return w;
        };
        // The level: each primitive's material textures and the lightmaps hemi uploaded.
        const render::SceneSurfaces& surfaces = level->surfaces();
        const render::TextureSet& textures = surfaces.textures();
        const render::TexelCoefficients &h6 = level->coefficients("h6"), &h4 = level->coefficients("h4"),
                                        &rnm = level->coefficients("ssbump");
        for (size_t p = 0; p < surfaces.primitive_count(); ++p)
        {
            const io::Material& m = surfaces.material(p);
            const VkDescriptorSet set = gpu::allocate_descriptor_set(device, pool, level_layout);
            const gpu::DescriptorWrite writes[] = {
                image_write(0, textures.sampler(m.base_color.sampler),
                            textures.image(m.base_color.image, true).view()),
                image_write(1, textures.sampler(m.normal.sampler),
                            textures.image(m.normal.image, false).view()),
                image_write(2, h6.sampler(), h6.pages().view()),
                image_write(3, h4.sampler(), h4.pages().view()),
                image_write(5, rnm.sampler(), rnm.pages().view()),
                image_write(8, h6.table_sampler(), h6.page_table().view()),
                image_write(9, h4.table_sampler(), h4.page_table().view()),
                image_write(10, rnm.table_sampler(), rnm.page_table().view())};
            gpu::write_descriptors(device, set, writes);
            level_sets.push_back(set);
        }
        // The torus: its textures and this frame's coefficients (hemi's transfer pass writes them).
        const render::SceneSurfaces& ts = torus->surfaces();
        for (size_t p = 0; p < ts.primitive_count(); ++p)
        {
            const io::Material& m = ts.material(p);
            const VkDescriptorSet set = gpu::allocate_descriptor_set(device, pool, prt_layout);
            gpu::DescriptorWrite coefficients;
            coefficients.binding = 4;
            coefficients.type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
            coefficients.texel_view = torus_coefficients;
            const gpu::DescriptorWrite writes[] = {
                image_write(0, ts.textures().sampler(m.base_color.sampler),
                            ts.textures().image(m.base_color.image, true).view()),
                image_write(1, ts.textures().sampler(m.normal.sampler),
                            ts.textures().image(m.normal.image, false).view()),
                coefficients};
            gpu::write_descriptors(device, set, writes);
            torus_sets.push_back(set);
        }
        env_set = gpu::allocate_descriptor_set(device, pool, env_layout);
        const gpu::DescriptorWrite env_writes[] = {image_write(6, sky->sampler(), sky->glossy_map().view()),
                                                   image_write(7, sky->sampler(), sky->diffuse_map().view())};
        gpu::write_descriptors(device, env_set, env_writes);

        // The shadow map is read with depth comparison (hardware PCF).
        VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
        s.magFilter = s.minFilter = VK_FILTER_LINEAR;
        s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        s.compareEnable = VK_TRUE;
        s.compareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
        s.maxLod = 0.0f;
        VkSampler raw;
        check(vkCreateSampler(vk, &s, nullptr, &raw), "vkCreateSampler");
        shadow_sampler = gpu::Sampler(vk, raw);
        gpu::SamplerDesc post;
        post.filter = VK_FILTER_NEAREST;
        post.address = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
        post.max_lod = 0.0f;
        post_sampler = gpu::create_sampler(device, post);

        for (Slot& slot : slots)
        {
            slot.uniforms = gpu::create_buffer(
                device, {sizeof(EngineFrame), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, gpu::MemoryUsage::Upload});
            if (!slot.uniforms.mapped())
                throw std::runtime_error("the device has no host-visible coherent memory for uniforms");
            slot.shadow = gpu::create_image(
                device, {kShadowSize, kShadowSize, kDepthFormat,
                         VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT});
            slot.shadow_fb =
                make_framebuffer(vk, shadow_pass, {slot.shadow.view()}, {kShadowSize, kShadowSize});
            slot.frame_set = gpu::allocate_descriptor_set(device, pool, frame_layout);
            gpu::DescriptorWrite ubo;
            ubo.binding = 0;
            ubo.type = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
            ubo.buffer = {slot.uniforms, 0, VK_WHOLE_SIZE};
            const gpu::DescriptorWrite writes[] = {
                ubo, image_write(1, shadow_sampler, slot.shadow.view(),
                                 VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL)};
            gpu::write_descriptors(device, slot.frame_set, writes);
            slot.post_set = gpu::allocate_descriptor_set(device, pool, post_layout);
        }
    }

    void create_pipelines()
    {
        const render::VertexLayout layout = render::GpuMesh::layout();
        const std::vector<VkVertexInputBindingDescription> bindings = {
            {0, layout.strides[0], VK_VERTEX_INPUT_RATE_VERTEX}};
        const std::vector<VkVertexInputAttributeDescription> attributes = {
            {0, 0, layout.position.format, layout.position.offset},
            {1, 0, layout.normal.format, layout.normal.offset},
            {2, 0, layout.tangent.format, layout.tangent.offset},
            {3, 0, layout.uv0.format, layout.uv0.offset},
            {4, 0, layout.uv1.format, layout.uv1.offset}};

        gpu::GraphicsProgramDesc d;
        d.vertex_bindings = bindings;
        d.vertex_attributes = {attributes[0]};
        d.push_constant_size = sizeof(EngineObject);
        d.set_layouts = {frame_layout};
        d.color_attachments = 0;
        d.render_pass = depth_pass;
        d.vertex_shader = spirv("depth.vert");
        depth_program = gpu::create_graphics_program(device, d);
        d.render_pass = shadow_pass;
        d.vertex_shader = spirv("depth_shadow.vert");
        d.depth_bias_constant = 1.25f;
        d.depth_bias_slope = 1.75f;
        shadow_program = gpu::create_graphics_program(device, d);

        gpu::GraphicsProgramDesc m;
        m.vertex_bindings = bindings;
        m.vertex_attributes = attributes;
        m.push_constant_size = sizeof(EngineObject);
        m.render_pass = main_pass;
        m.depth_write = false;
        m.depth_compare = VK_COMPARE_OP_LESS_OR_EQUAL; // against the prepass: each pixel shaded once
        m.vertex_shader = spirv("main.vert");
        m.set_layouts = {frame_layout, level_layout};
        m.fragment_shader = spirv("main_level.frag");
        m.specialization = {0, 4, 0};
        level_basis = gpu::create_graphics_program(device, m);
        m.specialization = {1, 4, 0};
        level_ssbump = gpu::create_graphics_program(device, m);
        const uint32_t k = uint32_t(torus->basis().size);
        m.vertex_shader = spirv("main_prt.vert");
        m.fragment_shader = spirv("main_prt.frag");
        m.set_layouts = {frame_layout, prt_layout};
        m.specialization = {0, k, uint32_t(torus->basis().id)};
        prt_program = gpu::create_graphics_program(device, m);
        m.vertex_shader = spirv("main.vert");
        m.fragment_shader = spirv("main_probe.frag");
        m.set_layouts = {frame_layout};
        m.specialization = {0, 4, 0};
        probe_program = gpu::create_graphics_program(device, m);
        m.fragment_shader = spirv("main_env.frag");
        m.set_layouts = {frame_layout, env_layout};
        env_program = gpu::create_graphics_program(device, m);

        gpu::GraphicsProgramDesc p;
        p.vertex_shader = spirv("post.vert");
        p.fragment_shader = spirv("post.frag");
        p.set_layouts = {post_layout};
        p.push_constant_size = sizeof(PostPush);
        p.render_pass = post_pass;
        p.depth_test = false;
        p.depth_write = false;
        p.cull_mode = VK_CULL_MODE_NONE;
        post_program = gpu::create_graphics_program(device, p);
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
            slot.depth = {};
            slot.hdr = {};
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
            slot.depth = gpu::create_image(
                device, {e.width, e.height, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT});
            slot.hdr =
                gpu::create_image(device, {e.width, e.height, kHdrFormat,
                                           VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT});
            slot.depth_fb = make_framebuffer(vk, depth_pass, {slot.depth.view()}, e);
            slot.main_fb = make_framebuffer(vk, main_pass, {slot.hdr.view(), slot.depth.view()}, e);
            gpu::DescriptorWrite w;
            w.binding = 0;
            w.type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
            w.image = {post_sampler, slot.hdr.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
            gpu::write_descriptors(device, slot.post_set, std::span<const gpu::DescriptorWrite>(&w, 1));
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

    // The probe-lit spheres circle the room's centre at three heights.
    glm::vec3 sphere_position(uint32_t i, float t) const
    {
        const float a = 0.35f * t + 2.0944f * float(i);
        return glm::vec3(1.9f * std::cos(a), 1.9f * std::sin(a), 0.45f + 0.5f * float(i));
    }

    FrameStats record(Slot& slot, uint32_t image, const Settings& settings, const FrameState& state,
                      bool screenshot)
    {
        const VkCommandBuffer cmd = slot.cmd;
        const VkExtent2D e = swapchain.extent;
        const float aspect = float(e.width) / float(e.height);
        FrameStats stats;

        // The frame's data, into this slot's mapped block (the slot's fence has passed: no frame reads it).
        EngineFrame f{};
        const glm::vec3 eye = settings.camera.eye;
        f.view_projection = math::camera_matrix(settings.camera, level_bounds, aspect);
        const float la = 0.5f * state.light_time;
        const glm::vec3 light_pos(1.6f * std::cos(la), 1.6f * std::sin(la), 2.8f);
        const glm::vec3 light_target(0.4f * std::cos(la + 1.0f), 0.4f * std::sin(la + 1.0f), 0.0f);
        const float cone = glm::radians(38.0f);
        f.light_view_projection =
            math::look_at_projection(light_pos, light_target, glm::degrees(2.0f * cone) + 4.0f, 1.0f);
        f.eye = glm::vec4(eye, settings.lod_distance);
        const bool light_on = settings.light && !settings.baked_only;
        f.light_position = glm::vec4(light_pos, light_on ? 1.0f : 0.0f);
        f.light_axis = glm::vec4(glm::normalize(light_target - light_pos), std::cos(cone));
        f.light_intensity = glm::vec4(9.0f, 8.0f, 6.5f, 0.0f);
        f.fog = glm::vec4(0.05f, 0.06f, 0.08f, settings.baked_only ? 0.0f : settings.fog);
        f.mode = glm::ivec4(settings.baked_only ? 2 : settings.basis, settings.lighting_only ? 1 : 0, 0, 0);
        const bool objects = settings.objects && !settings.baked_only;
        for (uint32_t s = 0; s < kSpheres; ++s)
        {
            std::array<glm::vec3, 9> sh;
            render::probe_lighting(assets.level, sphere_position(s, state.object_time), level_model, sh);
            for (uint32_t i = 0; i < 9; ++i)
                f.probe_sh[s * 9 + i] = glm::vec4(sh[i], 0.0f);
        }
        const float env_degrees = 25.0f * state.env_time;
        glossy.world_to_env =
            glm::mat3(glm::rotate(glm::mat4(1.0f), glm::radians(-env_degrees), glm::vec3(0.0f, 0.0f, 1.0f)));
        f.env = sky->uniforms(glossy);
        std::memcpy(slot.uniforms.mapped(), &f, sizeof f);

        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(cmd, &begin), "vkBeginCommandBuffer");

        // hemi's per-frame work, outside render passes: the torus relit by the turning sky, and the frame
        // sets of hemi's depth and shadow pipelines.
        if (objects)
        {
            render::PrtInstance instance;
            instance.model = torus_model;
            instance.world_lighting = assets.sky_sh;
            instance.rotate_degrees = env_degrees;
            torus->record_transfer(cmd, std::span<const render::PrtInstance>(&instance, 1));
        }
        render::FrameData camera_frame;
        camera_frame.view_projection = f.view_projection;
        camera_frame.eye = eye;
        camera_set->record_update(cmd, camera_frame);
        render::FrameData light_frame;
        light_frame.view_projection = f.light_view_projection;
        light_frame.eye = light_pos;
        light_set->record_update(cmd, light_frame);

        const std::vector<render::LightmapDraw> list = level->draw_list("h4", 0);
        auto draw_objects_depth =
            [&](const gpu::Program& program, size_t torus_pass, VkDescriptorSet hemi_frame)
        {
            if (!objects)
                return;
            torus->draw(cmd, hemi_frame, 0, torus_model, torus_pass);
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0, 1,
                                    &slot.frame_set, 0, nullptr);
            sphere->bind(cmd);
            for (uint32_t s = 0; s <= kSpheres; ++s)
            {
                EngineObject o;
                o.model = object_model(s, state);
                vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
                sphere->draw(cmd, 0, sphere->index_count());
            }
        };

        // 1. The shadow map from the spot light.
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
        if (light_on)
        {
            level->draw(cmd, light_set->set(), "h4", level_model, level_shadow);
            draw_objects_depth(shadow_program, torus_shadow, light_set->set());
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
            level->draw(cmd, camera_set->set(), *entry, level_model, level_depth);
        draw_objects_depth(depth_program, torus_depth, camera_set->set());
        vkCmdEndRenderPass(cmd);

        // 3. The main pass: the engine's own shaders over hemi's data.
        VkClearValue clears[2]{};
        clears[1].depthStencil = {1.0f, 0};
        rp.renderPass = main_pass;
        rp.framebuffer = slot.main_fb;
        rp.clearValueCount = 2;
        rp.pClearValues = clears;
        vkCmdBeginRenderPass(cmd, &rp, VK_SUBPASS_CONTENTS_INLINE);
        set_viewport(cmd, e);
        level->surfaces().mesh().bind(cmd);
        for (const render::LightmapDraw* entry : visible_entries)
        {
            const gpu::Program& program = *entry->technique == "ssbump" ? level_ssbump : level_basis;
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
            const VkDescriptorSet sets[2] = {slot.frame_set, level_sets[entry->primitive]};
            vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0, 2, sets, 0,
                                    nullptr);
            EngineObject o;
            o.model = level_model;
            o.albedo = entry->material->base_color_factor;
            vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
            level->surfaces().mesh().draw(cmd, entry->first_index, entry->index_count);
            ++stats.draws;
        }
        if (objects)
        {
            // The torus, relit this frame.
            vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, prt_program.pipeline);
            torus->mesh().bind(cmd);
            const render::SceneSurfaces& ts = torus->surfaces();
            for (size_t p = 0; p < ts.primitive_count(); ++p)
            {
                const VkDescriptorSet sets[2] = {slot.frame_set, torus_sets[p]};
                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, prt_program.layout, 0, 2, sets,
                                        0, nullptr);
                EngineObject o;
                o.model = torus_model;
                o.albedo = ts.material(p).base_color_factor;
                o.index.x = int32_t(torus->coefficients().instance_offset(0));
                vkCmdPushConstants(cmd, prt_program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
                const render::SceneSurfaces::Primitive prim = ts.primitive(p);
                torus->mesh().draw(cmd, prim.first_index, prim.index_count);
            }
            // The spheres lit by the probes, then the glossy ball.
            sphere->bind(cmd);
            const glm::vec4 colours[kSpheres] = {
                {0.9f, 0.3f, 0.25f, 1}, {0.9f, 0.85f, 0.8f, 1}, {0.3f, 0.5f, 0.9f, 1}};
            for (uint32_t s = 0; s <= kSpheres; ++s)
            {
                const gpu::Program& program = s < kSpheres ? probe_program : env_program;
                vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.pipeline);
                const VkDescriptorSet sets[2] = {slot.frame_set, env_set};
                vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, program.layout, 0,
                                        s < kSpheres ? 1 : 2, sets, 0, nullptr);
                EngineObject o;
                o.model = object_model(s, state);
                o.albedo = s < kSpheres ? colours[s] : glm::vec4(0.8f, 0.75f, 0.6f, 1.0f);
                o.index.x = int32_t(s);
                vkCmdPushConstants(cmd, program.layout, VK_SHADER_STAGE_ALL, 0, sizeof o, &o);
                sphere->draw(cmd, 0, sphere->index_count());
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
        screenshot_buffer =
            gpu::create_buffer(device, {VkDeviceSize(e.width) * e.height * 4,
                                        VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUsage::Readback});
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
        vkCmdCopyImageToBuffer(cmd, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, screenshot_buffer, 1, &copy);
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
        std::memcpy(img.pixels.data(), screenshot_buffer.mapped(), img.pixels.size());
        const bool bgra =
            swapchain.format == VK_FORMAT_B8G8R8A8_SRGB || swapchain.format == VK_FORMAT_B8G8R8A8_UNORM;
        for (size_t i = 0; i < img.pixels.size(); i += 4)
        {
            if (bgra)
                std::swap(img.pixels[i], img.pixels[i + 2]);
            img.pixels[i + 3] = 255;
        }
        io::write_png(path, img);
        screenshot_buffer = {};
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
        Slot& slot = slots[frame_index % kFramesInFlight];
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
        const FrameStats stats = record(slot, image, settings, state, shot);

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
