// The sections every baked asset shares (scene_sections.h): the mesh and the scene's surfaces.
#include "scene_sections.h"

#include <hemi/io/image.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>
#include <string>

namespace hemi::io
{
namespace
{

// ---- scene.materials: JSON, so that adding a material field later is not a layout change ----

using nlohmann::json;

const char* wrap_name(Wrap w)
{
    return w == Wrap::ClampToEdge      ? "clamp_to_edge"
           : w == Wrap::MirroredRepeat ? "mirrored_repeat"
                                       : "repeat";
}

json texture_json(const TextureRef& t)
{
    const TextureSampler& s = t.sampler;
    return {{"image", t.image},
            {"texcoord", t.texcoord},
            {"offset", {t.offset.x, t.offset.y}},
            {"scale", {t.scale.x, t.scale.y}},
            {"rotation", t.rotation},
            {"sampler",
             {{"mag", s.mag_filter == Filter::Nearest ? "nearest" : "linear"},
              {"min", s.min_filter == Filter::Nearest ? "nearest" : "linear"},
              {"mipmaps", s.mipmaps},
              {"wrap_s", wrap_name(s.wrap_s)},
              {"wrap_t", wrap_name(s.wrap_t)}}}};
}

std::string scene_json(const std::vector<Material>& materials_in, const std::vector<EncodedImage>& images_in)
{
    json materials = json::array(), images = json::array();
    for (const Material& m : materials_in)
    {
        json j = {
            {"name", m.name},
            {"base_color_factor",
             {m.base_color_factor.r, m.base_color_factor.g, m.base_color_factor.b, m.base_color_factor.a}},
            {"normal_scale", m.normal_scale},
            {"emissive_factor", {m.emissive_factor.r, m.emissive_factor.g, m.emissive_factor.b}},
            {"double_sided", m.double_sided}};
        if (m.occlusion.present())
            j["occlusion_strength"] = m.occlusion_strength;
        if (!m.technique.empty())
            j["technique"] = m.technique;
        if (m.alpha_mode != AlphaMode::Opaque)
        {
            j["alpha_mode"] = m.alpha_mode == AlphaMode::Mask ? "mask" : "blend";
            j["alpha_cutoff"] = m.alpha_cutoff;
        }
        for (const auto& [ref, key] :
             {std::pair{&m.base_color, "base_color"}, std::pair{&m.normal, "normal"},
              std::pair{&m.emissive, "emissive"}, std::pair{&m.occlusion, "occlusion"}})
            if (ref->present())
                j[key] = texture_json(*ref);
        materials.push_back(std::move(j));
    }
    for (const EncodedImage& im : images_in)
        images.push_back({{"name", im.name}, {"mime_type", im.mime_type}, {"bytes", im.bytes.size()}});
    return json{{"materials", std::move(materials)}, {"images", std::move(images)}}.dump();
}

// Strict reading of scene.materials: every field present with its type, numbers in range. nlohmann's own
// conversions would wrap a negative number into an unsigned one, so numbers are checked here.
struct SceneJson
{
    const std::string& file;

    [[noreturn]] void fail(const std::string& where, const std::string& what) const
    {
        throw FormatError(file + ": scene.materials: " + where + ": " + what);
    }
    const json& field(const json& j, const char* key, const std::string& where) const
    {
        if (!j.is_object() || !j.contains(key))
            fail(where, std::string("no '") + key + "'");
        return j[key];
    }
    float number(const json& j, const char* key, const std::string& where) const
    {
        const json& v = field(j, key, where);
        if (!v.is_number())
            fail(where, std::string("'") + key + "' is not a number");
        const float f = v.get<float>();
        if (!std::isfinite(f))
            fail(where, std::string("'") + key + "' is not finite");
        return f;
    }
    int64_t integer(const json& j, const char* key, int64_t lo, int64_t hi, const std::string& where) const
    {
        const json& v = field(j, key, where);
        if (!v.is_number_integer())
            fail(where, std::string("'") + key + "' is not an integer");
        const int64_t i =
            v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(INT64_MAX) ? INT64_MAX : v.get<int64_t>();
        if (i < lo || i > hi)
            fail(where, std::string("'") + key + "' = " + std::to_string(i) + " is not in [" +
                            std::to_string(lo) + ", " + std::to_string(hi) + "]");
        return i;
    }
    bool boolean(const json& j, const char* key, const std::string& where) const
    {
        const json& v = field(j, key, where);
        if (!v.is_boolean())
            fail(where, std::string("'") + key + "' is not true or false");
        return v.get<bool>();
    }
    std::string string(const json& j, const char* key, const std::string& where) const
    {
        const json& v = field(j, key, where);
        if (!v.is_string())
            fail(where, std::string("'") + key + "' is not a string");
        return v.get<std::string>();
    }
    template <int N> glm::vec<N, float> vec(const json& j, const char* key, const std::string& where) const
    {
        const json& v = field(j, key, where);
        if (!v.is_array() || v.size() != size_t(N))
            fail(where, std::string("'") + key + "' is not an array of " + std::to_string(N) + " numbers");
        glm::vec<N, float> out;
        for (int c = 0; c < N; ++c)
        {
            if (!v[size_t(c)].is_number() || !std::isfinite(v[size_t(c)].get<float>()))
                fail(where, std::string("'") + key + "' holds a value that is not a finite number");
            out[c] = v[size_t(c)].get<float>();
        }
        return out;
    }
    template <typename E>
    E choice(const json& j, const char* key, std::initializer_list<std::pair<const char*, E>> options,
             const std::string& where) const
    {
        const std::string v = string(j, key, where);
        for (const auto& [name, value] : options)
            if (v == name)
                return value;
        fail(where, std::string("'") + key + "' = '" + v + "' is not a known value");
    }

    TextureRef texture(const json& j, const std::string& where) const
    {
        TextureRef t;
        t.image = int(integer(j, "image", 0, INT32_MAX, where));
        t.texcoord = uint32_t(integer(j, "texcoord", 0, 1, where));
        t.offset = vec<2>(j, "offset", where);
        t.scale = vec<2>(j, "scale", where);
        t.rotation = number(j, "rotation", where);
        const json& s = field(j, "sampler", where);
        const std::string in = where + " sampler";
        t.sampler.mag_filter =
            choice<Filter>(s, "mag", {{"linear", Filter::Linear}, {"nearest", Filter::Nearest}}, in);
        t.sampler.min_filter =
            choice<Filter>(s, "min", {{"linear", Filter::Linear}, {"nearest", Filter::Nearest}}, in);
        t.sampler.mipmaps = boolean(s, "mipmaps", in);
        for (auto [key, wrap] :
             {std::pair{"wrap_s", &t.sampler.wrap_s}, std::pair{"wrap_t", &t.sampler.wrap_t}})
            *wrap = choice<Wrap>(s, key,
                                 {{"repeat", Wrap::Repeat},
                                  {"clamp_to_edge", Wrap::ClampToEdge},
                                  {"mirrored_repeat", Wrap::MirroredRepeat}},
                                 in);
        return t;
    }

    // Fills the materials and the images' names and mime types; returns each image's byte count.
    std::vector<uint64_t> read(std::span<const std::byte> bytes, std::vector<Material>& materials_out,
                               std::vector<EncodedImage>& images_out) const
    {
        json j;
        try
        {
            j = json::parse(reinterpret_cast<const char*>(bytes.data()),
                            reinterpret_cast<const char*>(bytes.data()) + bytes.size());
        }
        catch (const json::exception& e)
        {
            throw FormatError(file + ": scene.materials is not valid JSON (" + e.what() + ")");
        }
        const json& materials = field(j, "materials", "top level");
        const json& images = field(j, "images", "top level");
        if (!materials.is_array() || !images.is_array())
            fail("top level", "'materials' and 'images' must be arrays");
        for (size_t i = 0; i < materials.size(); ++i)
        {
            const json& m = materials[i];
            const std::string where = "material " + std::to_string(i);
            Material out;
            out.name = string(m, "name", where);
            out.base_color_factor = vec<4>(m, "base_color_factor", where);
            out.normal_scale = number(m, "normal_scale", where);
            out.emissive_factor = vec<3>(m, "emissive_factor", where);
            out.double_sided = boolean(m, "double_sided", where);
            for (const auto& [ref, key] :
                 {std::pair{&out.base_color, "base_color"}, std::pair{&out.normal, "normal"},
                  std::pair{&out.emissive, "emissive"}, std::pair{&out.occlusion, "occlusion"}})
                if (m.contains(key))
                    *ref = texture(m[key], where + " " + key);
            // Optional (assets written before hemi read occlusion textures have neither key).
            if (m.contains("occlusion_strength"))
                out.occlusion_strength = number(m, "occlusion_strength", where);
            if (m.contains("technique"))
                out.technique = string(m, "technique", where);
            // Optional: absent = opaque (and in assets written before hemi drew alpha).
            if (m.contains("alpha_mode"))
            {
                const std::string mode = string(m, "alpha_mode", where);
                if (mode != "mask" && mode != "blend")
                    fail(where, "alpha_mode '" + mode + "' is neither 'mask' nor 'blend'");
                out.alpha_mode = mode == "mask" ? AlphaMode::Mask : AlphaMode::Blend;
                out.alpha_cutoff = number(m, "alpha_cutoff", where);
                if (!(out.alpha_cutoff >= 0.0f))
                    fail(where, "alpha_cutoff is not a number >= 0");
            }
            materials_out.push_back(std::move(out));
        }
        std::vector<uint64_t> sizes;
        for (size_t i = 0; i < images.size(); ++i)
        {
            const std::string where = "image " + std::to_string(i);
            EncodedImage im;
            im.name = string(images[i], "name", where);
            im.mime_type = string(images[i], "mime_type", where);
            sizes.push_back(uint64_t(integer(images[i], "bytes", 1, INT64_MAX, where)));
            images_out.push_back(std::move(im));
        }
        return sizes;
    }
};

template <typename T> void add_array(AssetWriter& w, const std::string& name, const std::vector<T>& v)
{
    w.add_array(name, std::span<const T>(v));
}

} // namespace

void write_scene_sections(AssetWriter& w, const Mesh& mesh, const std::vector<Material>& materials,
                          const std::vector<EncodedImage>& images, const std::vector<Primitive>& primitives)
{
    add_array(w, "mesh.positions", mesh.positions);
    add_array(w, "mesh.normals", mesh.normals);
    add_array(w, "mesh.tangents", mesh.tangents);
    add_array(w, "mesh.uvs", mesh.uvs);
    add_array(w, "mesh.indices", mesh.indices);
    if (!mesh.uvs1.empty())
        add_array(w, "mesh.uvs1", mesh.uvs1);
    const std::string text = scene_json(materials, images);
    w.add("scene.materials", std::as_bytes(std::span<const char>(text)));
    std::vector<uint32_t> ranges;
    for (const Primitive& p : primitives)
        ranges.insert(ranges.end(), {p.first_index, p.index_count, p.material});
    add_array(w, "scene.primitives", ranges);
    for (size_t i = 0; i < images.size(); ++i)
        w.add("image." + std::to_string(i), std::as_bytes(std::span<const uint8_t>(images[i].bytes)));
}

void read_scene_sections(const AssetReader& r, const std::string& file, Mesh& mesh,
                         std::vector<Material>& materials, std::vector<EncodedImage>& images,
                         std::vector<Primitive>& primitives)
{
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(file + ": " + what); };
    mesh.positions = r.array<glm::vec3>("mesh.positions");
    mesh.normals = r.array<glm::vec3>("mesh.normals");
    mesh.tangents = r.array<glm::vec4>("mesh.tangents");
    mesh.uvs = r.array<glm::vec2>("mesh.uvs");
    mesh.indices = r.array<uint32_t>("mesh.indices");
    if (r.has("mesh.uvs1"))
        mesh.uvs1 = r.array<glm::vec2>("mesh.uvs1");

    // The surfaces: materials and image metadata, primitives, then each image's bytes.
    const std::vector<uint64_t> image_sizes =
        SceneJson{file}.read(r.section("scene.materials"), materials, images);
    const std::vector<uint32_t> ranges = r.array<uint32_t>("scene.primitives");
    if (ranges.size() % 3 != 0)
        throw fail("scene.primitives holds " + std::to_string(ranges.size()) +
                   " values, not (first, count, material) triples");
    for (size_t i = 0; i < ranges.size(); i += 3)
        primitives.push_back({ranges[i], ranges[i + 1], ranges[i + 2]});
    for (size_t i = 0; i < images.size(); ++i)
    {
        const std::string name = "image." + std::to_string(i);
        const std::span<const std::byte> b = r.section(name);
        if (b.size() != image_sizes[i])
            throw fail(name + " holds " + std::to_string(b.size()) + " bytes, scene.materials says " +
                       std::to_string(image_sizes[i]));
        const auto* p = reinterpret_cast<const uint8_t*>(b.data());
        images[i].bytes.assign(p, p + b.size());
    }
    std::set<std::string> listed;
    for (size_t i = 0; i < images.size(); ++i)
        listed.insert("image." + std::to_string(i));
    for (const std::string& section : r.names())
        if (section.rfind("image.", 0) == 0 && !listed.count(section))
            throw fail("section '" + section + "' is not one of the " + std::to_string(images.size()) +
                       " images scene.materials lists");
}

} // namespace hemi::io
