#include <hemi/math/sh.h>
#include <hemi/render/scene/lightmap_model.h>

#include <glm/matrix.hpp>

#include <cmath>
#include <stdexcept>

namespace hemi::render
{

const math::BasisDesc& lightmap_basis(const std::string& output)
{
    if (output == "plain")
        return math::vertex_irradiance_basis();
    if (output == "rnm" || output == "ssbump" || output == "rnm_ao")
        throw std::invalid_argument(
            "hemi: the 'rnm' lightmap colours are drawn by the rnm and ssbump techniques "
            "(radiosity normal mapping), not by a basis");
    return math::basis(output);
}

std::vector<glm::vec3> probe_lighting(const io::LightmapAsset& asset, const glm::vec3& world_position,
                                      const glm::mat4& model)
{
    if (asset.probes.empty())
        throw std::invalid_argument("hemi: the lightmap asset has no light probes (bake it with --probes)");
    if (!std::isfinite(world_position.x + world_position.y + world_position.z))
        throw std::invalid_argument("hemi: a probe-lit object's position is not finite");
    // The level's irradiance function f in its own frame is g(d) = f(R^T d) in the world: math::ShRotation(R)
    // with R the model's rotation (its uniform scale divided out).
    glm::mat3 rotation(model);
    const float scale = std::cbrt(std::abs(glm::determinant(rotation)));
    if (!(scale > 0.0f) || !std::isfinite(scale))
        throw std::invalid_argument("hemi: the model matrix is singular or not finite");
    rotation /= scale;
    const glm::vec3 p = glm::vec3(glm::inverse(model) * glm::vec4(world_position, 1.0f));
    const std::array<glm::vec3, 9> scene = asset.probes.at(p);
    std::vector<glm::vec3> world(9);
    math::ShRotation(3, rotation).apply(scene, world);
    return world;
}

LightmapModel::LightmapModel(MaterialSystem& system, const io::LightmapAsset& asset,
                             const std::vector<std::string>& techniques, gpu::UploadBatch& upload)
    : asset_(&asset)
{
    if (techniques.empty())
        throw std::invalid_argument("hemi: a lightmap model needs at least one technique");
    std::vector<SurfaceVariant> variants;
    for (const std::string& name : techniques)
    {
        // rnm and ssbump draw the "rnm" output (K = 3, carried by the 3-function HL2 basis's id); the others
        // their own output with their basis.
        const bool rnm = name == "rnm" || name == "ssbump" || name == "rnm_ao";
        if (name == "constant" && asset.outputs.empty())
            throw std::invalid_argument("hemi: the lightmap asset has no outputs");
        // "constant" (the base colour factor: hemi-bench's baseline) binds some output it does not read.
        const std::string source = rnm ? "rnm" : name == "constant" ? asset.outputs.front().name : name;
        const io::LightmapOutput& output = asset.output(source); // lists what the asset has
        if (rnm)
            variants.push_back({name == "rnm"      ? Technique::Rnm
                                : name == "rnm_ao" ? Technique::RnmAo
                                                   : Technique::Ssbump,
                                HEMI_BASIS_HL2});
        else if (source == "rnm")
            variants.push_back({Technique::Constant, HEMI_BASIS_HL2});
        else
            variants.push_back({name == "constant" ? Technique::Constant : Technique::Irradiance,
                                lightmap_basis(source).id});
        names_.push_back(name);
        coefficients_.push_back(std::make_unique<TexelCoefficients>(system, asset.width, asset.height,
                                                                    output.k, output.maps.dense(), upload));
    }
    surfaces_ =
        std::make_unique<SceneSurfaces>(system, asset.mesh, asset.images, asset.materials, asset.primitives,
                                        CoefficientSourceKind::Texel, variants, upload);
}

LightmapModel::~LightmapModel() = default;

void LightmapModel::draw(VkCommandBuffer cmd, VkDescriptorSet frame, const std::string& technique,
                         const glm::mat4& model, size_t pass) const
{
    for (size_t i = 0; i < names_.size(); ++i)
        if (names_[i] == technique)
        {
            surfaces_->draw(cmd, frame, coefficients_[i]->set(), 0, model, i, pass);
            return;
        }
    throw std::invalid_argument("hemi: technique '" + technique + "' is not loaded in this lightmap model");
}

} // namespace hemi::render
