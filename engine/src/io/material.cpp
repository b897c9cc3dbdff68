#include <hemi/io/image.h>
#include <hemi/io/material.h>
#include <hemi/io/mesh.h>

#include <cmath>
#include <cstring>

namespace hemi::io
{

void check_images(const std::vector<EncodedImage>& images, const std::string& container)
{
    for (size_t i = 0; i < images.size(); ++i)
    {
        try
        {
            decode_image(images[i]);
        }
        catch (const std::exception& e)
        {
            // decode_image names the image: an embedded one as "<container> image <i>", one by URI by it.
            const std::string message = e.what();
            throw FormatError(message.rfind(container, 0) == 0 ? message : container + ": " + message);
        }
    }
}

glm::mat3 TextureRef::uv_transform() const
{
    // T * R * S with R = [cos sin; -sin cos] (rows): see the header for why not the README's listing.
    const float c = std::cos(rotation), s = std::sin(rotation);
    glm::mat3 m(1.0f); // column-major: m[column][row]
    m[0] = glm::vec3(c * scale.x, -s * scale.x, 0.0f);
    m[1] = glm::vec3(s * scale.y, c * scale.y, 0.0f);
    m[2] = glm::vec3(offset, 1.0f);
    return m;
}

std::string sniff_image_mime_type(const uint8_t* bytes, size_t size)
{
    if (size >= 8 && std::memcmp(bytes, "\x89PNG\r\n\x1a\n", 8) == 0)
        return "image/png";
    if (size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF)
        return "image/jpeg";
    return {};
}

namespace
{
bool finite(const glm::vec2& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y);
}
bool finite(const glm::vec3& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const glm::vec4& v)
{
    return finite(glm::vec3(v)) && std::isfinite(v.w);
}

std::string texture_problem(const TextureRef& t, const char* slot, size_t images, bool has_uvs1)
{
    if (!t.present())
        return t.image == -1 ? std::string()
                             : std::string(slot) + " texture has image index " + std::to_string(t.image);
    if (size_t(t.image) >= images)
        return std::string(slot) + " texture refers to image " + std::to_string(t.image) +
               ", but there are " + std::to_string(images);
    if (t.texcoord > 1)
        return std::string(slot) + " texture reads TEXCOORD_" + std::to_string(t.texcoord) + " (0 or 1 only)";
    if (t.texcoord == 1 && !has_uvs1)
        return std::string(slot) + " texture reads TEXCOORD_1, which the mesh does not have";
    if (!finite(t.offset) || !finite(t.scale) || !std::isfinite(t.rotation))
        return std::string(slot) + " texture has a non-finite texture transform";
    if (uint8_t(t.sampler.wrap_s) > 2 || uint8_t(t.sampler.wrap_t) > 2 || uint8_t(t.sampler.mag_filter) > 1 ||
        uint8_t(t.sampler.min_filter) > 1)
        return std::string(slot) + " texture has an unknown sampler mode";
    return {};
}
} // namespace

std::string surface_problem(const Mesh& mesh, const std::vector<Material>& materials,
                            const std::vector<EncodedImage>& images, const std::vector<Primitive>& primitives)
{
    for (size_t i = 0; i < images.size(); ++i)
    {
        const EncodedImage& im = images[i];
        const std::string where = "image " + std::to_string(i) + " (" + im.name + "): ";
        if (im.mime_type != "image/png" && im.mime_type != "image/jpeg")
            return where + "mime type '" + im.mime_type + "' is neither image/png nor image/jpeg";
        if (im.bytes.empty())
            return where + "no bytes";
        if (sniff_image_mime_type(im.bytes.data(), im.bytes.size()) != im.mime_type)
            return where + "the bytes are not " + im.mime_type;
    }
    const bool has_uvs1 = !mesh.uvs1.empty();
    for (size_t i = 0; i < materials.size(); ++i)
    {
        const Material& m = materials[i];
        const std::string where = "material " + std::to_string(i) + " (" + m.name + "): ";
        if (!finite(m.base_color_factor) || !finite(m.emissive_factor) || !std::isfinite(m.normal_scale) ||
            !std::isfinite(m.occlusion_strength))
            return where + "non-finite factor";
        for (const auto& [ref, slot] :
             {std::pair{&m.base_color, "base colour"}, std::pair{&m.normal, "normal"},
              std::pair{&m.emissive, "emissive"}, std::pair{&m.occlusion, "occlusion"}})
            if (std::string p = texture_problem(*ref, slot, images.size(), has_uvs1); !p.empty())
                return where + p;
    }
    if (primitives.empty())
        return mesh.indices.empty() ? std::string() : "no primitives (every triangle needs a material)";
    uint64_t next = 0;
    for (size_t i = 0; i < primitives.size(); ++i)
    {
        const Primitive& p = primitives[i];
        const std::string where = "primitive " + std::to_string(i) + ": ";
        if (p.first_index != next)
            return where + "starts at index " + std::to_string(p.first_index) +
                   ", the previous one ends at " + std::to_string(next) +
                   " (primitives must follow each other)";
        if (p.index_count == 0 || p.index_count % 3 != 0)
            return where + std::to_string(p.index_count) + " indices, not a positive multiple of 3";
        if (p.material >= materials.size())
            return where + "material " + std::to_string(p.material) + " out of range (" +
                   std::to_string(materials.size()) + " materials)";
        next += p.index_count;
        if (next > mesh.indices.size())
            return where + "ends at index " + std::to_string(next) + ", past the mesh's " +
                   std::to_string(mesh.indices.size());
    }
    if (next != mesh.indices.size())
        return "the primitives cover " + std::to_string(next) + " of the mesh's " +
               std::to_string(mesh.indices.size()) + " indices";
    return {};
}

} // namespace hemi::io
