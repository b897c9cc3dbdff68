#pragma once
// hemi's material system: one surface shader for every technique, compiled into a pipeline per material
// key (technique x coefficient source x basis x frame x sidedness) for one render target, made once and
// cached. docs/materials.md describes the design; in short:
//
//   - A *material type* (MaterialType) is a compiled pipeline. Its key's axes that change bindings or
//     outputs (the coefficient source, the aux attachment) pick a SPIR-V variant; those that change code
//     only (basis, K, frame, technique, double-sidedness) are specialization constants.
//   - A *material instance* (MaterialInstance, material_instance.h) is one glTF material's factors and
//     textures: descriptor set 1, shared by every object drawn with it.
//   - A *coefficient source* (coefficient_source.h) is set 2: per object instance, its transfer-pass
//     output (per vertex), its coefficient textures (per texel) or its probe (uniform).
//   - Set 0 is the frame (camera, options: FrameSet, frame_set.h). Per draw, the model matrix and the
//     object's coefficient offset go by push constants (shared::DrawPush).
//
// Clip-space conventions: Vulkan's (x right, y down, depth 0 at the near plane to 1 at the far one, as
// glm::perspectiveRH_ZO with the y row negated produces). Front faces are counter-clockwise seen from
// outside in hemi's meshes (glTF's rule); single-sided materials cull back faces. Reverse-Z is the
// caller's projection plus depth_compare = VK_COMPARE_OP_GREATER(_OR_EQUAL) and a depth clear of 0.

#include <hemi/gpu/descriptors.h>
#include <hemi/gpu/device.h>
#include <hemi/gpu/handle.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/io/material.h>

#include "hemi/shared/bases.h"
#include "hemi/shared/surface.h"

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <tuple>
#include <vector>

namespace hemi::render
{

enum class Technique : uint32_t
{
    Irradiance = HEMI_TECHNIQUE_IRRADIANCE, // basis at the normal: PRT, classic PRT, lightmaps, SH probes
    Constant = HEMI_TECHNIQUE_CONSTANT,     // the base colour factor alone (a baseline, a debug view)
    Rnm = HEMI_TECHNIQUE_RNM,       // radiosity normal mapping, Green 2007 Listing 1 (K = 3: rnm colours)
    Ssbump = HEMI_TECHNIQUE_SSBUMP, // self-shadowed bump map in the normal slot, Listing 2 (K = 3)
    RnmAo = HEMI_TECHNIQUE_RNM_AO,  // Listing 1 times the material's occlusion texture (Green's baseline)
    // Heidrich & Seidel 1999, with the environment source (render::EnvironmentLighting), world frame:
    Factored = HEMI_TECHNIQUE_FACTORED, // Torrance-Sparrow from its factor tables for the dynamic lights
    Banks = HEMI_TECHNIQUE_BANKS,       // Banks' anisotropic model from its table for the dynamic lights
    EnvMirror =
        HEMI_TECHNIQUE_ENV_MIRROR, // Fresnel-weighted mirror reflection of the parabolic map + diffuse
    EnvGlossy = HEMI_TECHNIQUE_ENV_GLOSSY, // the prefiltered glossy map at the reflection vector + diffuse
    // The material's textures (base colour, normal map, emissive) lit by the frame's dynamic lights alone
    // (Lambert at the normal-map normal), no precomputed lighting: hemi-bench's fair baseline.
    Lambert = HEMI_TECHNIQUE_LAMBERT,
    // Irradiance plus the specular of the frame's GGX coat from the coefficients (hemi_coefficient_specular;
    // FrameData::glossy_roughness): lightmap technique names "<output>+ggx".
    Ggx = HEMI_TECHNIQUE_GGX,
};

enum class CoefficientSourceKind : uint32_t
{
    Vertex = HEMI_SOURCE_VERTEX,           // transfer or CPCA pass output, interpolated across triangles
    Texel = HEMI_SOURCE_TEXEL,             // coefficient textures sampled at TEXCOORD_1
    Uniform = HEMI_SOURCE_UNIFORM,         // K coefficients per object from a storage buffer (ProbeBuffer)
    Environment = HEMI_SOURCE_ENVIRONMENT, // parabolic environment maps and BRDF tables (EnvironmentLighting)
};

enum class ShadingFrame : uint32_t
{
    Tangent = HEMI_FRAME_TANGENT, // coefficients in each vertex's (or texel's) normal-map tangent frame
    World = HEMI_FRAME_WORLD,     // coefficients in world space (the normal map is turned into it)
};

// Where one vertex attribute of the surface shader comes from: a vertex buffer binding (a stream) and a
// format that the device reads as a vertex attribute (VK_FORMAT_FEATURE_VERTEX_BUFFER_BIT). The shader reads
// position as vec3, normal as vec3, the glTF tangent as vec4 (w: handedness) and the UV sets as vec2:
// narrower formats are widened by the input assembler (fp16, snorm, unorm), so an engine's packed meshes
// draw without conversion; a format with fewer components reads the missing ones as 0 (w as 1).
struct VertexInput
{
    uint32_t binding = 0; // the stream: 0 .. kMaxVertexStreams - 1
    VkFormat format = VK_FORMAT_UNDEFINED;
    uint32_t offset = 0; // bytes from the vertex's start in its stream

    auto tie() const { return std::tie(binding, format, offset); }
};

// The vertex layout a material type reads: the five attributes and the stride of each stream they use. Every
// attribute must be present (an object without lightmap UVs points uv1 at uv0). The index type is not part
// of it: the caller binds its own index buffer, 16- or 32-bit. Default: GpuMesh's layout (one interleaved
// fp32 stream of 56 bytes).
struct VertexLayout
{
    static constexpr uint32_t kMaxVertexStreams = 4;
    VertexInput position{0, VK_FORMAT_R32G32B32_SFLOAT, 0};
    VertexInput normal{0, VK_FORMAT_R32G32B32_SFLOAT, 12};
    VertexInput tangent{0, VK_FORMAT_R32G32B32A32_SFLOAT, 24};
    VertexInput uv0{0, VK_FORMAT_R32G32_SFLOAT, 40};
    VertexInput uv1{0, VK_FORMAT_R32G32_SFLOAT, 48};
    uint32_t strides[kMaxVertexStreams] = {56, 0, 0, 0}; // bytes per vertex of each stream (0: unused)

    auto tie() const
    {
        return std::tie(position.binding, position.format, position.offset, normal.binding, normal.format,
                        normal.offset, tangent.binding, tangent.format, tangent.offset, uv0.binding,
                        uv0.format, uv0.offset, uv1.binding, uv1.format, uv1.offset, strides[0], strides[1],
                        strides[2], strides[3]);
    }
    bool operator<(const VertexLayout& o) const { return tie() < o.tie(); }
    bool operator==(const VertexLayout& o) const { return tie() == o.tie(); }
};

// How a lightmap (a Texel coefficient source) is looked up: the linear filter, or the cubic B-spline, which
// shows no crease at texel centres in gradients and costs four linear fetches per packed layer instead of one
// (hemi_lightmap_coefficients_bicubic, docs/glsl.md).
enum class LightmapFilter
{
    Linear = HEMI_LIGHTMAP_FILTER_LINEAR,
    Bicubic = HEMI_LIGHTMAP_FILTER_BICUBIC,
};

struct MaterialKey
{
    Technique technique = Technique::Irradiance;
    CoefficientSourceKind source = CoefficientSourceKind::Vertex;
    int basis = HEMI_BASIS_SH9; // HEMI_BASIS_*: an entry of math::bases(), or classic PRT's vertex irradiance
    ShadingFrame frame = ShadingFrame::Tangent;
    bool double_sided = false; // glTF doubleSided: no culling (world frame: back faces lit with -N)
    VertexLayout vertex{};     // the meshes' vertex layout (default: GpuMesh's)
    // glTF alphaMode: Mask discards where alpha < the material's alphaCutoff; Blend blends over attachment 0
    // without writing depth (the caller draws blended surfaces after the opaque ones, back to front).
    io::AlphaMode alpha = io::AlphaMode::Opaque;
    LightmapFilter lightmap_filter = LightmapFilter::Linear; // Texel sources only (others ignore it)

    auto tie() const
    {
        return std::tie(technique, source, basis, frame, double_sided, vertex, alpha, lightmap_filter);
    }
    bool operator<(const MaterialKey& o) const { return tie() < o.tie(); }
    bool operator==(const MaterialKey& o) const { return tie() == o.tie(); }
};

// Where materials draw and how: a subpass of a render pass, or dynamic rendering (render_pass null; the
// device must have it: gpu::Device::dynamic_rendering()).
struct RenderTargetDesc
{
    VkRenderPass render_pass = VK_NULL_HANDLE;
    uint32_t subpass = 0;
    uint32_t color_attachments = 1;              // render pass: colour attachments of the subpass
    std::vector<VkFormat> color_formats;         // dynamic rendering: one per colour attachment
    VkFormat depth_format = VK_FORMAT_UNDEFINED; // dynamic rendering: UNDEFINED = no depth attachment
    // Colour attachment 1 receives (u, v, draw id, 1) where the mesh covers the pixel (hemi's
    // OffscreenTarget; shared::DrawPush::draw_id, e.g. PrtModel's primitive index + 1); otherwise only
    // attachment 0 is written. Further attachments are the engine's: hemi's pipelines leave them as they are
    // (on devices with independentBlend: gpu::Device::independent_blend(); else they are written too).
    bool aux_output = false;
    VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
    bool depth_test = true;
    bool depth_write = true;
    VkCompareOp depth_compare = VK_COMPARE_OP_LESS; // reverse-Z: VK_COMPARE_OP_GREATER_OR_EQUAL
};

// What a pass of the engine's frame draws, and so which pipeline of a material key it needs:
//   Color:  the technique's colour into the target's attachments;
//   Depth:  depth only (a depth prepass): no fragment shader but for alpha-tested (Mask, and Blend when
//           the caller draws it) materials, which discard where alpha < alphaCutoff; colour attachments, if
//           the target has any, are not written;
//   Shadow: Depth with depth bias (a shadow map from the light's view: the FrameSet the caller binds).
// The technique, basis and frame do not change a depth pipeline: keys that differ only in them share one.
enum class PassKind : uint32_t
{
    Color,
    Depth,
    Shadow,
};

struct PassDesc
{
    PassKind kind = PassKind::Color;
    RenderTargetDesc target;
    // Shadow: the rasteriser's depth bias (constant in units of the depth format's resolution, and times
    // the polygon's depth slope).
    float depth_bias_constant = 1.25f, depth_bias_slope = 1.75f;

    auto tie() const
    {
        return std::tie(kind, target.render_pass, target.subpass, target.color_attachments,
                        target.color_formats, target.depth_format, target.aux_output, target.samples,
                        target.depth_test, target.depth_write, target.depth_compare, depth_bias_constant,
                        depth_bias_slope);
    }
    bool operator<(const PassDesc& o) const { return tie() < o.tie(); }
};

// A compiled material type: the pipeline of one key for one pass and target.
struct MaterialType
{
    MaterialKey key;
    PassKind pass = PassKind::Color;
    uint32_t k = 0;       // coefficients the basis takes
    gpu::Program program; // pipeline + layout (sets 0-2 of the system's shared layouts, shared::DrawPush)
    uint32_t id = 0; // 0, 1, 2, ... in the order the system compiled its types: a draw sort key's pipeline
    const gpu::Device* device = nullptr; // the system's: where a refused draw of this type is reported
};

class MaterialSystem
{
  public:
    // `target` is the default pass's (a Color pass into it): what type(key) compiles for. Every object made
    // with the system (material instances, coefficient sources) draws in any pass: the descriptor set
    // layouts are the system's, not a pass's. `cache` is the host's VkPipelineCache (or null); it must
    // outlive the system.
    MaterialSystem(const gpu::Device& device, const RenderTargetDesc& target,
                   VkPipelineCache cache = VK_NULL_HANDLE);
    // A system without a default pass, for an engine that draws colour with its own shaders: loading a model
    // compiles no pipeline, and each object's passes are the ones it is given (add_pass: the first is 0).
    // type(key) without a pass throws.
    explicit MaterialSystem(const gpu::Device& device, VkPipelineCache cache = VK_NULL_HANDLE);
    ~MaterialSystem();
    MaterialSystem(const MaterialSystem&) = delete;
    MaterialSystem& operator=(const MaterialSystem&) = delete;

    // The type of `key`, compiled on first use (at set-up, ideally: prepare() every key a scene needs),
    // then cached. Throws std::invalid_argument for a basis hemi does not know, or a vertex layout with a
    // stream out of range or without a stride, or a format the device cannot read as a vertex attribute
    // (naming the attribute and the format).
    const MaterialType& type(const MaterialKey& key);
    // The type of `key` for `pass` (its kind and target), compiled on first use and cached per (key, pass).
    // Safe to call from several threads at once (the compile runs outside the cache's lock).
    const MaterialType& type(const MaterialKey& key, const PassDesc& pass);
    // Compiles every key for `pass` now (at load time, so that no draw waits for a pipeline).
    void prepare(std::span<const MaterialKey> keys, const PassDesc& pass);
    // Whether the system was made with a default target (the models' pass 0), and that pass.
    bool has_default_pass() const { return has_default_pass_; }
    const PassDesc& default_pass() const { return default_pass_; }
    size_t type_count() const;

    // The shared layouts of sets 0 (frame), 1 (material) and 2 (per coefficient source).
    VkDescriptorSetLayout frame_layout() const { return frame_layout_; }
    VkDescriptorSetLayout material_layout() const { return material_layout_; }
    VkDescriptorSetLayout source_layout(CoefficientSourceKind kind) const;

    // The bindings of each set, for descriptor pools (frame_set.h, material_instance.h,
    // coefficient_source.h).
    static std::vector<gpu::Binding> frame_bindings();
    static std::vector<gpu::Binding> material_bindings();
    static std::vector<gpu::Binding> source_bindings(CoefficientSourceKind kind);

    const gpu::Device& device() const { return *device_; }
    const RenderTargetDesc& target() const { return default_pass_.target; }

    // Where every material instance, coefficient source, frame set and environment made with this system gets
    // its descriptor set: one growable allocator (a pool per 1,024 sets), thread-safe. Those objects must be
    // destroyed before the system.
    gpu::DescriptorAllocator& descriptors() const { return *descriptors_; }

  private:
    std::unique_ptr<MaterialType> compile(const MaterialKey& key, const PassDesc& pass) const;

    const gpu::Device* device_;
    PassDesc default_pass_;
    bool has_default_pass_ = false;
    VkPipelineCache cache_;
    gpu::DescriptorSetLayout frame_layout_, material_layout_;
    gpu::DescriptorSetLayout source_layouts_[4];
    std::unique_ptr<gpu::DescriptorAllocator> descriptors_;
    mutable std::mutex mutex_;
    std::map<std::pair<MaterialKey, PassDesc>, std::unique_ptr<MaterialType>> types_;
};

// What one draw binds: the type (pipeline), the three sets, the per-draw push constants.
struct DrawBindings
{
    const MaterialType* type = nullptr;
    VkDescriptorSet frame = VK_NULL_HANDLE;
    VkDescriptorSet material = VK_NULL_HANDLE;
    VkDescriptorSet source = VK_NULL_HANDLE;
    shared::DrawPush push{};
};
// Binds the pipeline, the sets and the push constants (inside the caller's render pass or rendering).
void bind_material(VkCommandBuffer cmd, const DrawBindings& draw);

} // namespace hemi::render
