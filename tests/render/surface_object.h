#pragma once
// Tests' way of drawing a procedural mesh with a normal map through the material system, composed from the
// engine's parts exactly as an engine would: GpuMesh, TextureSet + MaterialInstance (set 1), a coefficient
// set (set 2) and a material type from the MaterialSystem.
#include <hemi/gpu/upload.h>
#include <hemi/math/basis.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/material_instance.h>
#include <hemi/render/material/material_system.h>
#include <hemi/render/scene/gpu_mesh.h>
#include <hemi/render/transfer.h>

#include <memory>

namespace hemi::test
{

struct SurfaceObject
{
    gpu::UploadBatch upload;
    render::GpuMesh mesh;
    io::Material material;
    render::TextureSet textures;
    render::MaterialInstance instance;
    std::unique_ptr<render::VertexCoefficients> vertex;
    std::unique_ptr<render::ProbeBuffer> probe;
    const render::MaterialType* type = nullptr;
    VkDescriptorSet source_set = VK_NULL_HANDLE; // overrides the vertex or probe set (e.g. coefficient maps)

    // Per-vertex coefficients from `source` (tangent frame, basis `basis`), or, with source null, an SH9
    // probe in world space. `normal_map` is image 0.
    SurfaceObject(render::MaterialSystem& system, const io::Mesh& m, const io::ImageRgba8& normal_map,
                  const io::Material& mat, const math::BasisDesc& basis,
                  const render::CoefficientSource* source)
        : upload(system.device()), mesh(system.device(), m, upload), material(mat),
          textures(system.device(), std::span<const io::ImageRgba8>(&normal_map, 1),
                   std::span<const io::Material>(&material, 1), upload),
          instance(system, textures, material, upload)
    {
        render::MaterialKey key;
        key.basis = basis.id;
        key.double_sided = material.double_sided;
        if (source)
        {
            vertex = std::make_unique<render::VertexCoefficients>(
                system, source->coefficients(), source->instance_stride() * source->instances());
            key.source = render::CoefficientSourceKind::Vertex;
            key.frame = render::ShadingFrame::Tangent;
        }
        else
        {
            probe = std::make_unique<render::ProbeBuffer>(system, 1);
            key.source = render::CoefficientSourceKind::Uniform;
            key.frame = render::ShadingFrame::World;
        }
        type = &system.type(key);
    }

    // Inside the render pass.
    void draw(VkCommandBuffer cmd, VkDescriptorSet frame, const glm::mat4& model = glm::mat4(1.0f),
              uint32_t coefficient_offset = 0) const
    {
        render::DrawBindings b;
        b.type = type;
        b.frame = frame;
        b.material = instance.set();
        b.source = source_set ? source_set : vertex ? vertex->set() : probe->set();
        b.push.model = model;
        b.push.coefficient_offset = coefficient_offset;
        render::bind_material(cmd, b);
        mesh.bind(cmd);
        mesh.draw(cmd, 0, mesh.index_count());
    }
};

// A material with `albedo` and the normal map as image 0, sampled bilinearly from mip 0 (glTF minFilter
// LINEAR): what the tests' CPU references evaluate (normal_map_lookup.h).
// A 2 x 2 quad in the xz plane facing -y (towards a camera on -y), UV (0, 0) at its top left; TEXCOORD_1 =
// TEXCOORD_0.
inline io::Mesh quad()
{
    io::Mesh m;
    m.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
    m.normals.assign(4, glm::vec3(0, -1, 0));
    m.tangents.assign(4, glm::vec4(1, 0, 0, 1));
    m.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
    m.uvs1 = m.uvs;
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

inline io::Material normal_mapped(glm::vec3 albedo)
{
    io::Material m;
    m.base_color_factor = glm::vec4(albedo, 1.0f);
    m.normal.image = 0;
    m.normal.sampler.mipmaps = false;
    return m;
}

} // namespace hemi::test
