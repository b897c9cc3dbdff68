#include <hemi/io/atomic_file.h>
#include <hemi/io/gltf.h>
#include <hemi/io/image.h>

#include "gltf_builder.h"

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <new>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace hemi::io
{
namespace
{

std::string mode_name(int mode)
{
    switch (mode)
    {
    case TINYGLTF_MODE_POINTS:
        return "POINTS";
    case TINYGLTF_MODE_LINE:
        return "LINES";
    case TINYGLTF_MODE_LINE_LOOP:
        return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP:
        return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLES:
        return "TRIANGLES";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
        return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN:
        return "TRIANGLE_FAN";
    default:
        return "mode " + std::to_string(mode);
    }
}

bool is_integer_type(int t)
{
    return t == TINYGLTF_COMPONENT_TYPE_BYTE || t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
           t == TINYGLTF_COMPONENT_TYPE_SHORT || t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
           t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

bool is_unsigned_type(int t)
{
    return t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
           t == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
}

// One component as glTF defines its value: floats as they are, normalised integers mapped to [0, 1] or
// [-1, 1] (glTF 2.0, 3.11), other integers as their value. The caller has checked the type.
double component(const unsigned char* p, int type, bool normalized)
{
    switch (type)
    {
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
    {
        float f;
        std::memcpy(&f, p, 4);
        return f;
    }
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    {
        const double v = double(int8_t(*p));
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? *p / 255.0 : double(*p);
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    {
        int16_t s;
        std::memcpy(&s, p, 2);
        return normalized ? std::max(s / 32767.0, -1.0) : double(s);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
    {
        uint16_t s;
        std::memcpy(&s, p, 2);
        return normalized ? s / 65535.0 : double(s);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    {
        uint32_t u;
        std::memcpy(&u, p, 4);
        return normalized ? u / 4294967295.0 : double(u);
    }
    default:
        return 0.0;
    }
}

// One line per feature: the first occurrence is named, later ones are counted, so a scene with a thousand
// skinned nodes gives one warning, not a thousand.
class Warnings
{
  public:
    void add(const std::string& feature, const std::string& message)
    {
        for (Entry& e : entries_)
            if (e.feature == feature)
            {
                ++e.more;
                return;
            }
        entries_.push_back({feature, message, 0});
    }
    std::vector<std::string> lines() const
    {
        std::vector<std::string> out;
        for (const Entry& e : entries_)
            out.push_back(e.more ? e.message + " (and " + std::to_string(e.more) + " more like it)"
                                 : e.message);
        return out;
    }

  private:
    struct Entry
    {
        std::string feature, message;
        size_t more;
    };
    std::vector<Entry> entries_;
};

// Extensions hemi reads, and those whose absence only simplifies how the scene looks. Any other extension in
// extensionsRequired means hemi cannot know what the file's data mean: a FormatError.
const std::set<std::string> kSupportedExtensions = {"KHR_texture_transform", "KHR_mesh_quantization",
                                                    "KHR_materials_emissive_strength", "KHR_lights_punctual"};
bool appearance_only(const std::string& ext)
{
    static const std::set<std::string> known = {
        "KHR_texture_basisu", "EXT_texture_webp",       "EXT_texture_avif",     "MSFT_texture_dds", "KHR_xmp",
        "KHR_xmp_json_ld",    "EXT_lights_image_based", "KHR_animation_pointer"};
    return ext.rfind("KHR_materials_", 0) == 0 || known.count(ext) != 0;
}
const std::set<std::string> kImageExtensions = {"KHR_texture_basisu", "EXT_texture_webp", "EXT_texture_avif",
                                                "MSFT_texture_dds"};

// RFC 3986 percent-decoding of a URI path. Returns false on a malformed escape.
bool percent_decode(const std::string& in, std::string& out)
{
    auto hex = [](char c)
    {
        if (c >= '0' && c <= '9')
            return c - '0';
        if (c >= 'a' && c <= 'f')
            return c - 'a' + 10;
        if (c >= 'A' && c <= 'F')
            return c - 'A' + 10;
        return -1;
    };
    out.clear();
    for (size_t i = 0; i < in.size(); ++i)
    {
        if (in[i] != '%')
        {
            out.push_back(in[i]);
            continue;
        }
        if (i + 2 >= in.size() || hex(in[i + 1]) < 0 || hex(in[i + 2]) < 0)
            return false;
        out.push_back(char(hex(in[i + 1]) * 16 + hex(in[i + 2])));
        i += 2;
    }
    return true;
}

std::string percent_encode(const std::string& in)
{
    static const char* digits = "0123456789ABCDEF";
    std::string out;
    for (unsigned char c : in)
    {
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' ||
            c == '.' || c == '_' || c == '~' || c == '/')
            out.push_back(char(c));
        else
        {
            out.push_back('%');
            out.push_back(digits[c >> 4]);
            out.push_back(digits[c & 15]);
        }
    }
    return out;
}

// A glTF primitive's vertices and triangles, local indices, before they join the scene's mesh: tangent and
// normal generation work on this, so their scratch arrays are the primitive's size, not the scene's.
struct Part
{
    Mesh mesh;
    bool has_uvs1 = false;
};

void generate_normals(Mesh& m)
{
    m.normals.assign(m.positions.size(), glm::vec3(0.0f));
    for (size_t i = 0; i + 2 < m.indices.size(); i += 3)
    {
        const uint32_t a = m.indices[i], b = m.indices[i + 1], c = m.indices[i + 2];
        const glm::vec3 n =
            glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]); // area-weighted
        m.normals[a] += n, m.normals[b] += n, m.normals[c] += n;
    }
    for (glm::vec3& n : m.normals)
    {
        const float len = glm::length(n);
        n = len > 0 ? n / len : glm::vec3(0, 0, 1);
    }
}

void generate_tangents(Mesh& m)
{
    // MikkTSpace's construction: each triangle's UV tangent and bitangent, projected into the plane of
    // each corner's vertex normal and normalised, are accumulated weighted by the corner's angle (so a
    // vertex's frame does not depend on how finely its neighbourhood is tessellated).
    const size_t n = m.positions.size();
    std::vector<glm::vec3> t(n, glm::vec3(0.0f)), b(n, glm::vec3(0.0f));
    auto unit_in_plane = [](const glm::vec3& v, const glm::vec3& normal)
    {
        const glm::vec3 p = v - normal * glm::dot(normal, v);
        const float len = glm::length(p);
        return len > 1e-20f ? p / len : glm::vec3(0.0f);
    };
    for (size_t i = 0; i + 2 < m.indices.size(); i += 3)
    {
        const uint32_t idx[3] = {m.indices[i], m.indices[i + 1], m.indices[i + 2]};
        const glm::vec3 e1 = m.positions[idx[1]] - m.positions[idx[0]],
                        e2 = m.positions[idx[2]] - m.positions[idx[0]];
        const glm::vec2 d1 = m.uvs[idx[1]] - m.uvs[idx[0]], d2 = m.uvs[idx[2]] - m.uvs[idx[0]];
        const float det = d1.x * d2.y - d2.x * d1.y;
        if (std::abs(det) < 1e-20f)
            continue;
        // dP/du and dP/dv of the triangle; glTF's bitangent points toward -v (DESIGN.md, io/mesh.h).
        const glm::vec3 dpdu = (e1 * d2.y - e2 * d1.y) / det, dpdv = (e2 * d1.x - e1 * d2.x) / det;
        for (int c = 0; c < 3; ++c)
        {
            const uint32_t v = idx[c];
            const glm::vec3& normal = m.normals[v];
            const glm::vec3 a = unit_in_plane(m.positions[idx[(c + 1) % 3]] - m.positions[v], normal);
            const glm::vec3 e = unit_in_plane(m.positions[idx[(c + 2) % 3]] - m.positions[v], normal);
            // A corner whose edges vanish in the normal's plane says nothing about the frame: no weight.
            const float angle = glm::dot(a, a) > 0.0f && glm::dot(e, e) > 0.0f
                                    ? std::acos(std::clamp(glm::dot(a, e), -1.0f, 1.0f))
                                    : 0.0f;
            t[v] += angle * unit_in_plane(dpdu, normal);
            b[v] -= angle * unit_in_plane(dpdv, normal);
        }
    }
    m.tangents.resize(n);
    for (size_t v = 0; v < n; ++v)
    {
        const glm::vec3 nn = m.normals[v];
        glm::vec3 tt = t[v] - nn * glm::dot(nn, t[v]);
        const float len = glm::length(tt);
        if (len < 1e-12f) // no UV gradient: any tangent perpendicular to the normal
            tt = glm::normalize(std::abs(nn.x) < 0.9f ? glm::cross(nn, glm::vec3(1, 0, 0))
                                                      : glm::cross(nn, glm::vec3(0, 1, 0)));
        else
            tt /= len;
        const float w = glm::dot(glm::cross(nn, tt), b[v]) < 0.0f ? -1.0f : 1.0f;
        m.tangents[v] = glm::vec4(tt, w);
    }
}

struct Reader
{
    std::string file;
    const tinygltf::Model& model;
    std::filesystem::path dir;
    Warnings warnings;
    GltfScene scene;
    std::vector<int> image_of; // glTF image -> index in scene.images, -1 until a material uses it
    int default_material = -1;
    bool any_uvs1 = false;
    std::vector<std::string> without_uvs1; // primitives lacking TEXCOORD_1 ("mesh 2 primitive 0")
    size_t skipped = 0;                    // point and line primitives
    bool lights_placed = false;            // a node placed a KHR_lights_punctual light

    [[noreturn]] void fail(const std::string& what) const { throw FormatError(file + ": " + what); }

    struct Run
    {
        const unsigned char* data = nullptr;
        size_t stride = 0;
    };

    // Where `count` elements of `element` bytes lie in buffer view `view_index`, from byte `offset` of the
    // view. Overflow-safe: a hostile count (2^62) must not wrap the end offset around to something small, so
    // the element count is compared with a quotient of sizes that are known to fit rather than multiplied.
    Run locate(int view_index, size_t offset, size_t count, size_t element, bool strided,
               const std::string& what) const
    {
        if (view_index < 0 || size_t(view_index) >= model.bufferViews.size())
            fail(what + ": buffer view " + std::to_string(view_index) + " does not exist");
        const tinygltf::BufferView& view = model.bufferViews[size_t(view_index)];
        if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size())
            fail(what + ": buffer view " + std::to_string(view_index) + " has no buffer");
        const std::vector<unsigned char>& data = model.buffers[size_t(view.buffer)].data;
        const bool meshopt = view.extensions.count("EXT_meshopt_compression") != 0;
        auto past = [&](const std::string& detail)
        {
            fail(what + " reads past its buffer (" + detail + ")" +
                 (meshopt
                      ? "; the buffer view is EXT_meshopt_compression data without an uncompressed fallback"
                      : ""));
        };
        if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
            past("buffer view " + std::to_string(view_index) + " spans " + std::to_string(view.byteLength) +
                 " bytes from byte " + std::to_string(view.byteOffset) + " of a " +
                 std::to_string(data.size()) + "-byte buffer");
        const size_t stride = strided && view.byteStride ? view.byteStride : element;
        if (stride < element)
            fail(what + ": buffer view " + std::to_string(view_index) + " has a stride of " +
                 std::to_string(stride) + " bytes, less than its " + std::to_string(element) +
                 "-byte elements");
        if (count == 0)
            return {};
        const size_t length = view.byteLength;
        if (offset > length || element > length - offset || count - 1 > (length - offset - element) / stride)
            past(std::to_string(count) + " elements of " + std::to_string(element) + " bytes every " +
                 std::to_string(stride) + " bytes from byte " + std::to_string(offset) + " of a " +
                 std::to_string(length) + "-byte buffer view");
        return {data.data() + view.byteOffset + offset, stride};
    }

    // Reads accessor `index` as `components` values per element: floats (T = float) or indices (T = uint32_t,
    // unsigned integer components only). Sparse accessors and accessors without a buffer view (zeros) too.
    template <typename T> std::vector<T> read(int index, int components, const std::string& what) const
    {
        constexpr bool indices = std::is_integral_v<T>;
        const std::string where = what + ": accessor " + std::to_string(index);
        if (index < 0 || size_t(index) >= model.accessors.size())
            fail(where + " does not exist");
        const tinygltf::Accessor& a = model.accessors[size_t(index)];
        if (tinygltf::GetNumComponentsInType(uint32_t(a.type)) != components)
            fail(where + " has the wrong type (" +
                 std::to_string(tinygltf::GetNumComponentsInType(uint32_t(a.type))) +
                 " components, expected " + std::to_string(components) + ")");
        const int type = a.componentType;
        if (indices ? !is_unsigned_type(type)
                    : !(type == TINYGLTF_COMPONENT_TYPE_FLOAT || is_integer_type(type)))
            fail(where + " has an unsupported component type " + std::to_string(type));
        const size_t csize = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(type)));
        const size_t element = csize * size_t(components);
        // An accessor without a buffer view is all zeros (glTF 2.0, 3.6.2.3), usually with sparse values on
        // top, and nothing in the file bounds its count: cap it at what 32-bit indices can address.
        if (a.bufferView < 0 && a.count > std::numeric_limits<uint32_t>::max())
            fail(where + " has no buffer view and " + std::to_string(a.count) + " elements");
        Run run;
        if (a.bufferView >= 0)
            run = locate(a.bufferView, a.byteOffset, a.count, element, true, where);
        std::vector<T> out(a.count * size_t(components)); // bounded by the buffer's size or 2^32 elements
        auto store = [&](size_t i, const unsigned char* p)
        {
            for (int c = 0; c < components; ++c)
            {
                const double v = component(p + size_t(c) * csize, type, !indices && a.normalized);
                if constexpr (!indices)
                    if (!std::isfinite(v))
                        fail("non-finite value in " + where);
                out[i * size_t(components) + size_t(c)] = T(v);
            }
        };
        if (run.data)
            for (size_t i = 0; i < a.count; ++i)
                store(i, run.data + i * run.stride);
        if (a.sparse.isSparse)
        {
            const auto& s = a.sparse;
            if (s.count < 1 || size_t(s.count) > a.count)
                fail(where + ": sparse count " + std::to_string(s.count) + " is not in [1, " +
                     std::to_string(a.count) + "]");
            if (s.indices.byteOffset < 0 || s.values.byteOffset < 0)
                fail(where + ": negative sparse byte offset");
            const int itype = s.indices.componentType;
            if (!is_unsigned_type(itype))
                fail(where + ": sparse indices of component type " + std::to_string(itype));
            const size_t isize = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(itype)));
            const Run ind = locate(s.indices.bufferView, size_t(s.indices.byteOffset), size_t(s.count), isize,
                                   false, where + " (sparse indices)");
            const Run val = locate(s.values.bufferView, size_t(s.values.byteOffset), size_t(s.count), element,
                                   false, where + " (sparse values)");
            uint64_t previous = 0;
            for (size_t k = 0; k < size_t(s.count); ++k)
            {
                const uint64_t target = uint64_t(component(ind.data + k * isize, itype, false));
                if (target >= a.count || (k > 0 && target <= previous))
                    fail(where + ": sparse index " + std::to_string(target) +
                         " is out of range or not increasing");
                previous = target;
                store(size_t(target), val.data + k * element);
            }
        }
        return out;
    }

    // ---- materials and images ----

    EncodedImage load_image(int g)
    {
        const tinygltf::Image& img = model.images[size_t(g)];
        const std::string label =
            "image " + std::to_string(g) + (img.name.empty() ? "" : " (" + img.name + ")");
        EncodedImage e;
        std::string declared = img.mimeType;
        if (img.bufferView >= 0)
        {
            const Run run = locate(img.bufferView, 0, 1, 1, false, label);
            const size_t length = model.bufferViews[size_t(img.bufferView)].byteLength;
            e.bytes.assign(run.data, run.data + length);
            e.name = file + " " + label;
        }
        else if (!img.uri.empty())
        {
            // tinygltf decodes data URIs of the media types it knows and leaves the URI of any other.
            if (img.uri.rfind("data:", 0) == 0)
                fail(label + ": a data URI of an unsupported type (" + img.uri.substr(0, img.uri.find(',')) +
                     "); glTF images are PNG or JPEG");
            const size_t colon = img.uri.find(':'), slash = img.uri.find('/');
            if (colon != std::string::npos && (slash == std::string::npos || colon < slash) && colon > 1)
                fail(label + ": URI '" + img.uri +
                     "' is not a relative file path (hemi reads local files only)");
            std::string relative;
            if (!percent_decode(img.uri, relative))
                fail(label + ": malformed percent-encoding in URI '" + img.uri + "'");
            const std::filesystem::path p = dir / std::filesystem::path(relative);
            std::error_code ec;
            if (!std::filesystem::is_regular_file(p, ec))
                fail(label + ": " + p.string() + " does not exist");
            try
            {
                e = read_encoded_image(p);
            }
            catch (const FormatError& error)
            {
                fail(label + ": " + error.what());
            }
            e.name = relative;
        }
        else if (!img.image.empty()) // a data URI, captured by the image loader (read_gltf)
        {
            e.bytes = img.image;
            e.name = file + " " + label + " (data URI)";
        }
        else
            fail(label + " has no data (neither a buffer view nor a URI)");
        e.mime_type = sniff_image_mime_type(e.bytes.data(), e.bytes.size());
        if (e.mime_type.empty())
            fail(label + " is neither PNG nor JPEG" +
                 (declared.empty() ? "" : " (declared " + declared + ")") +
                 "; glTF 2.0 images are PNG or JPEG");
        if (!declared.empty() && declared != e.mime_type)
            warnings.add("mime", label + " declares " + declared + " but holds " + e.mime_type +
                                     " bytes; read as " + e.mime_type);
        return e;
    }

    TextureSampler sampler(int s)
    {
        TextureSampler out;
        if (s < 0)
            return out;
        if (size_t(s) >= model.samplers.size())
            fail("sampler " + std::to_string(s) + " does not exist");
        const tinygltf::Sampler& in = model.samplers[size_t(s)];
        auto wrap = [&](int mode)
        {
            switch (mode)
            {
            case TINYGLTF_TEXTURE_WRAP_REPEAT:
                return Wrap::Repeat;
            case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE:
                return Wrap::ClampToEdge;
            case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT:
                return Wrap::MirroredRepeat;
            default:
                warnings.add("wrap", "sampler " + std::to_string(s) + ": unknown wrap mode " +
                                         std::to_string(mode) + " read as REPEAT");
                return Wrap::Repeat;
            }
        };
        out.wrap_s = wrap(in.wrapS);
        out.wrap_t = wrap(in.wrapT);
        out.mag_filter = in.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST ? Filter::Nearest : Filter::Linear;
        switch (in.minFilter)
        {
        case TINYGLTF_TEXTURE_FILTER_NEAREST:
            out.min_filter = Filter::Nearest, out.mipmaps = false;
            break;
        case TINYGLTF_TEXTURE_FILTER_LINEAR:
            out.min_filter = Filter::Linear, out.mipmaps = false;
            break;
        case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST:
        case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR:
            out.min_filter = Filter::Nearest, out.mipmaps = true;
            break;
        default:
            out.min_filter = Filter::Linear, out.mipmaps = true;
            break; // unspecified, *_MIPMAP_* with LINEAR
        }
        return out;
    }

    static bool read_vec2(const tinygltf::Value& v, glm::vec2& out)
    {
        if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber())
            return false;
        out = glm::vec2(float(v.Get(0).GetNumberAsDouble()), float(v.Get(1).GetNumberAsDouble()));
        return std::isfinite(out.x) && std::isfinite(out.y);
    }

    TextureRef texture(int index, int texcoord, const tinygltf::ExtensionMap& extensions,
                       const std::string& slot, const std::string& material)
    {
        TextureRef ref;
        if (index < 0)
            return ref;
        const std::string where = material + "'s " + slot;
        if (size_t(index) >= model.textures.size())
            fail(where + " refers to texture " + std::to_string(index) + ", which does not exist");
        const tinygltf::Texture& tex = model.textures[size_t(index)];
        bool told = false;
        for (const auto& entry : tex.extensions)
            if (kImageExtensions.count(entry.first))
            {
                warnings.add(entry.first,
                             entry.first + " ignored: texture " + std::to_string(index) +
                                 (tex.source >= 0 ? " is read from its PNG/JPEG fallback"
                                                  : " has no PNG/JPEG image; " + where + " is left out"));
                told = true;
            }
        if (tex.source < 0)
        {
            if (!told)
                warnings.add("no source",
                             "texture " + std::to_string(index) + " has no image; " + where + " is left out");
            return ref;
        }
        if (size_t(tex.source) >= model.images.size())
            fail("texture " + std::to_string(index) + " refers to image " + std::to_string(tex.source) +
                 ", which does not exist");
        if (image_of[size_t(tex.source)] < 0)
        {
            image_of[size_t(tex.source)] = int(scene.images.size());
            scene.images.push_back(load_image(tex.source));
        }
        ref.image = image_of[size_t(tex.source)];
        ref.sampler = sampler(tex.sampler);
        if (auto it = extensions.find("KHR_texture_transform"); it != extensions.end())
        {
            const tinygltf::Value& t = it->second;
            if (!t.IsObject())
                fail(where + ": KHR_texture_transform is not an object");
            if (t.Has("offset") && !read_vec2(t.Get("offset"), ref.offset))
                fail(where + ": KHR_texture_transform offset is not two finite numbers");
            if (t.Has("scale") && !read_vec2(t.Get("scale"), ref.scale))
                fail(where + ": KHR_texture_transform scale is not two finite numbers");
            if (t.Has("rotation"))
            {
                const tinygltf::Value& r = t.Get("rotation");
                ref.rotation = r.IsNumber() ? float(r.GetNumberAsDouble()) : NAN;
                if (!std::isfinite(ref.rotation))
                    fail(where + ": KHR_texture_transform rotation is not a finite number");
            }
            if (t.Has("texCoord")) // overrides the textureInfo's
            {
                if (!t.Get("texCoord").IsInt())
                    fail(where + ": KHR_texture_transform texCoord is not an integer");
                texcoord = t.Get("texCoord").GetNumberAsInt();
            }
        }
        if (texcoord < 0)
            fail(where + " reads TEXCOORD_" + std::to_string(texcoord));
        if (texcoord > 1)
        {
            warnings.add("texcoord", where + " reads TEXCOORD_" + std::to_string(texcoord) +
                                         ", which hemi does not support; it reads TEXCOORD_0");
            texcoord = 0;
        }
        ref.texcoord = uint32_t(texcoord);
        return ref;
    }

    Material material(size_t i)
    {
        const tinygltf::Material& in = model.materials[i];
        const std::string label =
            "material " + std::to_string(i) + (in.name.empty() ? "" : " (" + in.name + ")");
        Material m;
        m.name = in.name;
        const std::vector<double>& bc = in.pbrMetallicRoughness.baseColorFactor;
        const std::vector<double>& em = in.emissiveFactor;
        if (bc.size() != 4 || em.size() != 3)
            fail(label + ": baseColorFactor needs 4 values and emissiveFactor 3");
        m.base_color_factor = glm::vec4(float(bc[0]), float(bc[1]), float(bc[2]), float(bc[3]));
        m.emissive_factor = glm::vec3(float(em[0]), float(em[1]), float(em[2]));
        m.normal_scale = float(in.normalTexture.scale);
        for (int c = 0; c < 4; ++c)
            if (!std::isfinite(m.base_color_factor[c]) || (c < 3 && !std::isfinite(m.emissive_factor[c])))
                fail(label + ": non-finite colour factor");
        if (!std::isfinite(m.normal_scale))
            fail(label + ": non-finite normal texture scale");
        const auto& pbr = in.pbrMetallicRoughness;
        m.base_color = texture(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                               pbr.baseColorTexture.extensions, "base colour texture", label);
        m.normal = texture(in.normalTexture.index, in.normalTexture.texCoord, in.normalTexture.extensions,
                           "normal texture", label);
        m.emissive = texture(in.emissiveTexture.index, in.emissiveTexture.texCoord,
                             in.emissiveTexture.extensions, "emissive texture", label);
        m.occlusion = texture(in.occlusionTexture.index, in.occlusionTexture.texCoord,
                              in.occlusionTexture.extensions, "occlusion texture", label);
        m.occlusion_strength = float(in.occlusionTexture.strength);
        if (!std::isfinite(m.occlusion_strength))
            fail(label + ": non-finite occlusion strength");
        m.double_sided = in.doubleSided;
        if (in.extras.IsObject() && in.extras.Has("hemi_technique"))
        {
            const tinygltf::Value& t = in.extras.Get("hemi_technique");
            if (!t.IsString() || t.Get<std::string>().empty())
                fail(label + ": extras.hemi_technique is not a technique name");
            m.technique = t.Get<std::string>();
        }
        if (in.alphaMode == "MASK" || in.alphaMode == "BLEND")
        {
            m.alpha_mode = in.alphaMode == "MASK" ? io::AlphaMode::Mask : io::AlphaMode::Blend;
            m.alpha_cutoff = float(in.alphaCutoff);
            if (!std::isfinite(m.alpha_cutoff) || m.alpha_cutoff < 0.0f)
                fail(label + ": alphaCutoff is not a finite number >= 0");
            warnings.add("alphaMode " + in.alphaMode,
                         "alphaMode " + in.alphaMode + " baked opaque (drawn with alpha): " + label);
        }
        else if (in.alphaMode != "OPAQUE")
            warnings.add("alphaMode", "unknown alphaMode '" + in.alphaMode + "' drawn opaque: " + label);
        for (const auto& [name, value] : in.extensions)
        {
            if (name == "KHR_materials_emissive_strength")
            {
                const tinygltf::Value& s = value.IsObject() ? value.Get("emissiveStrength") : value;
                const double strength = s.IsNumber() ? s.GetNumberAsDouble() : 1.0;
                if (!std::isfinite(strength) || strength < 0.0)
                    fail(label + ": KHR_materials_emissive_strength is not a finite number >= 0");
                m.emissive_factor *= float(strength);
            }
            else
                warnings.add(name, name + " ignored: " + label +
                                       " is drawn with its base colour, normal and "
                                       "emissive inputs only");
        }
        return m;
    }

    // ---- geometry ----

    uint32_t material_of(const tinygltf::Primitive& prim, const std::string& where)
    {
        if (prim.material >= 0)
        {
            if (size_t(prim.material) >= model.materials.size())
                fail(where + " refers to material " + std::to_string(prim.material) +
                     ", which does not exist");
            return uint32_t(prim.material);
        }
        if (default_material < 0)
        {
            default_material = int(scene.materials.size());
            Material m;
            m.name = "default";
            scene.materials.push_back(m);
        }
        return uint32_t(default_material);
    }

    // The triangle list of a primitive (local indices, as the file winds them), or false for points and
    // lines.
    bool triangles(const tinygltf::Primitive& prim, size_t count, const std::string& where,
                   std::vector<uint32_t>& out)
    {
        const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
            mode == TINYGLTF_MODE_LINE_STRIP)
        {
            warnings.add("mode " + mode_name(mode), mode_name(mode) + " primitives are not drawn: " + where +
                                                        " skipped (hemi draws triangles)");
            ++skipped;
            return false;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN)
            fail(where + ": unknown primitive mode " + std::to_string(mode));
        std::vector<uint32_t> idx;
        if (prim.indices >= 0)
            idx = read<uint32_t>(prim.indices, 1, "indices");
        else
        {
            idx.resize(count);
            for (size_t v = 0; v < count; ++v)
                idx[v] = uint32_t(v);
        }
        for (uint32_t i : idx)
            if (i >= count)
                fail(where + ": index " + std::to_string(i) + " out of range (" + std::to_string(count) +
                     " vertices)");
        if (mode == TINYGLTF_MODE_TRIANGLES)
        {
            if (idx.size() % 3 != 0)
                fail(where + ": index count " + std::to_string(idx.size()) + " is not a multiple of 3");
            out = std::move(idx);
            return true;
        }
        // Strips and fans as glTF 2.0 (3.7.2.1) defines their triangles; the degenerate ones exporters use to
        // join strips cover no area and are dropped.
        out.clear();
        for (size_t i = 2; i < idx.size(); ++i)
        {
            uint32_t a, b, c;
            if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
            {
                const size_t k = i - 2;
                a = idx[k], b = idx[k + 1 + k % 2], c = idx[k + 2 - k % 2];
            }
            else
                a = idx[i - 1], b = idx[i], c = idx[0];
            if (a != b && b != c && a != c)
                out.insert(out.end(), {a, b, c});
        }
        return true;
    }

    void add_primitive(const tinygltf::Primitive& prim, const std::string& where, const glm::mat4& world)
    {
        for (const auto& entry : prim.extensions)
            if (entry.first == "KHR_draco_mesh_compression")
                warnings.add(entry.first, "KHR_draco_mesh_compression ignored: " + where +
                                              " is read from its uncompressed fallback");
        const auto pos_it = prim.attributes.find("POSITION");
        if (pos_it == prim.attributes.end())
            fail(where + " has no POSITION");
        if (prim.extensions.count("KHR_draco_mesh_compression") &&
            size_t(pos_it->second) < model.accessors.size() &&
            model.accessors[size_t(pos_it->second)].bufferView < 0 &&
            !model.accessors[size_t(pos_it->second)].sparse.isSparse)
            fail(where +
                 " is KHR_draco_mesh_compression-compressed without an uncompressed fallback; hemi does not "
                 "decode Draco: re-export the scene without mesh compression");
        const std::vector<float> pos = read<float>(pos_it->second, 3, "POSITION");
        const size_t count = pos.size() / 3;
        std::vector<uint32_t> local;
        if (!triangles(prim, count, where, local) || local.empty())
            return;
        if (!prim.targets.empty())
            warnings.add("morph targets", "morph targets ignored: " + where + " is drawn in its base shape");
        std::vector<float> nrm, tan, uv, uv1;
        for (const auto& [name, accessor] : prim.attributes)
        {
            if (name == "NORMAL")
                nrm = read<float>(accessor, 3, "NORMAL");
            else if (name == "TANGENT")
                tan = read<float>(accessor, 4, "TANGENT");
            else if (name == "TEXCOORD_0")
                uv = read<float>(accessor, 2, "TEXCOORD_0");
            else if (name == "TEXCOORD_1")
                uv1 = read<float>(accessor, 2, "TEXCOORD_1");
            else if (name.rfind("COLOR_", 0) == 0)
                warnings.add("COLOR", "vertex colours (" + name + ") ignored: " + where);
            else if (name.rfind("TEXCOORD_", 0) == 0)
                warnings.add("TEXCOORD", name + " ignored (hemi reads TEXCOORD_0 and TEXCOORD_1): " + where);
        }
        if ((!nrm.empty() && nrm.size() != count * 3) || (!tan.empty() && tan.size() != count * 4) ||
            (!uv.empty() && uv.size() != count * 2) || (!uv1.empty() && uv1.size() != count * 2))
            fail(where + ": attribute counts differ from POSITION's");
        if (uint64_t(scene.mesh.positions.size()) + count > std::numeric_limits<uint32_t>::max())
            fail("more than 2^32 vertices");

        const glm::mat3 linear(world);
        const glm::mat3 normal_matrix = glm::inverseTranspose(linear);
        const float handedness = glm::determinant(linear) < 0.0f ? -1.0f : 1.0f;
        Mesh part;
        part.positions.resize(count);
        part.normals.resize(count);
        part.tangents.resize(count);
        part.uvs.resize(count);
        bool bad_normals = false, bad_tangents = false;
        for (size_t v = 0; v < count; ++v)
        {
            part.positions[v] =
                glm::vec3(world * glm::vec4(pos[v * 3], pos[v * 3 + 1], pos[v * 3 + 2], 1.0f));
            if (!nrm.empty())
            {
                const glm::vec3 n = normal_matrix * glm::vec3(nrm[v * 3], nrm[v * 3 + 1], nrm[v * 3 + 2]);
                const float len = glm::length(n);
                bad_normals |= !(len > 1e-20f) || !std::isfinite(len);
                // glm::normalize, not n / len: the bits hemi has always read (bakes reproduce exactly).
                part.normals[v] = len > 1e-20f ? glm::normalize(n) : glm::vec3(0.0f);
            }
            if (!tan.empty())
            {
                const glm::vec3 t = linear * glm::vec3(tan[v * 4], tan[v * 4 + 1], tan[v * 4 + 2]);
                const float len = glm::length(t);
                bad_tangents |= !(len > 1e-20f) || !std::isfinite(len);
                part.tangents[v] = glm::vec4(len > 1e-20f ? glm::normalize(t) : glm::vec3(0.0f),
                                             (tan[v * 4 + 3] < 0.0f ? -1.0f : 1.0f) * handedness);
            }
            if (!uv.empty())
                part.uvs[v] = glm::vec2(uv[v * 2], uv[v * 2 + 1]);
        }
        // A mirroring node (negative determinant) turns counter-clockwise triangles clockwise (glTF 2.0,
        // 3.7.4): swap two corners so that every triangle stays counter-clockwise seen from outside.
        part.indices.resize(local.size());
        for (size_t t = 0; t < local.size(); t += 3)
        {
            part.indices[t] = local[t];
            part.indices[t + 1] = local[handedness < 0.0f ? t + 2 : t + 1];
            part.indices[t + 2] = local[handedness < 0.0f ? t + 1 : t + 2];
        }
        if (nrm.empty() || bad_normals)
        {
            if (bad_normals)
                warnings.add("zero normals", where + " has zero-length normals; its normals are generated");
            generate_normals(part);
        }
        if (tan.empty() || bad_tangents || bad_normals)
        {
            if (bad_tangents)
                warnings.add("zero tangents",
                             where + " has zero-length tangents; its tangents are generated");
            generate_tangents(part);
            scene.tangents_generated = true;
        }

        Primitive range;
        range.first_index = uint32_t(scene.mesh.indices.size());
        range.index_count = uint32_t(local.size());
        range.material = material_of(prim, where);
        scene.primitives.push_back(range);
        if (uv1.empty())
            without_uvs1.push_back(where);
        else
            any_uvs1 = true;
        Mesh& m = scene.mesh;
        const uint32_t first = uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), part.positions.begin(), part.positions.end());
        m.normals.insert(m.normals.end(), part.normals.begin(), part.normals.end());
        m.tangents.insert(m.tangents.end(), part.tangents.begin(), part.tangents.end());
        m.uvs.insert(m.uvs.end(), part.uvs.begin(), part.uvs.end());
        for (size_t v = 0; v < count; ++v) // zeros where absent; dropped at the end when no primitive has any
            m.uvs1.push_back(uv1.empty() ? glm::vec2(0.0f) : glm::vec2(uv1[v * 2], uv1[v * 2 + 1]));
        for (uint32_t i : part.indices)
            m.indices.push_back(first + i);
    }

    void add_mesh(int mesh_index, const glm::mat4& world)
    {
        if (mesh_index < 0 || size_t(mesh_index) >= model.meshes.size())
            fail("a node refers to mesh " + std::to_string(mesh_index) + ", which does not exist");
        const tinygltf::Mesh& mesh = model.meshes[size_t(mesh_index)];
        for (size_t p = 0; p < mesh.primitives.size(); ++p)
            add_primitive(mesh.primitives[p],
                          "mesh " + std::to_string(mesh_index) + " primitive " + std::to_string(p), world);
    }

    glm::mat4 local_matrix(size_t node) const
    {
        const tinygltf::Node& n = model.nodes[node];
        for (const std::vector<double>* v : {&n.matrix, &n.translation, &n.rotation, &n.scale})
            for (double x : *v)
                if (!std::isfinite(x))
                    fail("node " + std::to_string(node) + " has a non-finite transform");
        if (n.matrix.size() == 16)
            return glm::mat4(glm::make_mat4(n.matrix.data()));
        glm::mat4 m(1.0f);
        if (n.translation.size() == 3)
            m = glm::translate(
                m, glm::vec3(float(n.translation[0]), float(n.translation[1]), float(n.translation[2])));
        if (n.rotation.size() == 4)
        {
            glm::quat q(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]),
                        float(n.rotation[2]));
            const float len = glm::length(q); // glTF requires unit quaternions; exporters round
            m *= glm::mat4_cast(len > 0.0f ? q / len : glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
        }
        if (n.scale.size() == 3)
            m = glm::scale(m, glm::vec3(float(n.scale[0]), float(n.scale[1]), float(n.scale[2])));
        return m;
    }

    // Depth-first, parents before children, in the order the file lists them (what a recursive walk gives),
    // with an explicit stack (a deep chain of nodes must not overflow the call stack) and every node visited
    // once: glTF's hierarchy is a forest (2.0, 3.5.3), and a node listed twice, as a child of two parents or
    // as both a root and a child would otherwise be drawn twice -- or, when each node lists the next one
    // twice, 2^N times.
    void walk(const std::vector<int>& roots, const std::string& scene_label)
    {
        std::vector<char> visited(model.nodes.size(), 0);
        struct Item
        {
            int node, parent;
            glm::mat4 parent_world;
        };
        std::vector<Item> stack;
        for (auto it = roots.rbegin(); it != roots.rend(); ++it)
            stack.push_back({*it, -1, glm::mat4(1.0f)});
        while (!stack.empty())
        {
            const Item item = stack.back();
            stack.pop_back();
            const std::string from = item.parent < 0 ? scene_label : "node " + std::to_string(item.parent);
            if (item.node < 0 || size_t(item.node) >= model.nodes.size())
                fail(from + " refers to node " + std::to_string(item.node) + ", which does not exist");
            if (visited[size_t(item.node)])
                fail("node " + std::to_string(item.node) + " is reached twice (again from " + from +
                     "): the node hierarchy must be a forest, each node with at most one parent");
            visited[size_t(item.node)] = 1;
            const tinygltf::Node& n = model.nodes[size_t(item.node)];
            const glm::mat4 world = item.parent_world * local_matrix(size_t(item.node));
            if (n.mesh >= 0)
            {
                if (n.skin >= 0)
                {
                    // A skinned mesh's vertices are in the bind pose already (with every joint at the inverse
                    // of its inverse bind matrix they stay where they are) and glTF ignores the skinned
                    // node's own transform (2.0, 3.7.3.1): drawn as stored.
                    warnings.add("skins", "skins are not supported: node " + std::to_string(item.node) +
                                              " is drawn in its bind pose");
                    add_mesh(n.mesh, glm::mat4(1.0f));
                }
                else
                    add_mesh(n.mesh, world);
                if (n.extensions.count("EXT_mesh_gpu_instancing"))
                    warnings.add("EXT_mesh_gpu_instancing", "EXT_mesh_gpu_instancing ignored: node " +
                                                                std::to_string(item.node) + " is drawn once");
            }
            if (const auto light = n.extensions.find("KHR_lights_punctual"); light != n.extensions.end())
                add_light(item.node, light->second, world);
            if (n.name.rfind(kLightProbeNodePrefix, 0) == 0) // a light probe placed by hand
            {
                const glm::vec3 at(world[3]);
                if (!std::isfinite(at.x + at.y + at.z))
                    fail("node " + std::to_string(item.node) + " (\"" + n.name +
                         "\"), a light probe, is placed at a point that is not finite");
                scene.light_probes.push_back(at);
            }
            for (auto it = n.children.rbegin(); it != n.children.rend(); ++it)
                stack.push_back({*it, item.node, world});
        }
    }

    // A node's KHR_lights_punctual reference: the light, checked, placed by the node's world transform.
    void add_light(int node, const tinygltf::Value& ext, const glm::mat4& world)
    {
        const std::string where = "node " + std::to_string(node) + " KHR_lights_punctual";
        if (!ext.IsObject() || !ext.Has("light") || !ext.Get("light").IsNumber())
            fail(where + ": no light index");
        const int index = ext.Get("light").GetNumberAsInt();
        if (index < 0 || size_t(index) >= model.lights.size())
            fail(where + ": light " + std::to_string(index) + " does not exist (the file has " +
                 std::to_string(model.lights.size()) + ")");
        const tinygltf::Light& l = model.lights[size_t(index)];
        const std::string what =
            "light " + std::to_string(index) + (l.name.empty() ? "" : " (" + l.name + ")");
        PunctualLight out;
        out.name = l.name;
        if (l.type == "directional")
            out.type = PunctualLight::Type::Directional;
        else if (l.type == "point")
            out.type = PunctualLight::Type::Point;
        else if (l.type == "spot")
            out.type = PunctualLight::Type::Spot;
        else
            fail(what + ": unknown type '" + l.type + "'");
        if (!l.color.empty())
        {
            if (l.color.size() != 3)
                fail(what + ": color must have 3 components");
            out.color = glm::vec3(float(l.color[0]), float(l.color[1]), float(l.color[2]));
        }
        out.intensity = float(l.intensity);
        out.range = float(l.range);
        out.inner_cone = float(l.spot.innerConeAngle);
        out.outer_cone = float(l.spot.outerConeAngle);
        if (!std::isfinite(out.color.r) || !std::isfinite(out.color.g) || !std::isfinite(out.color.b) ||
            out.color.r < 0 || out.color.g < 0 || out.color.b < 0)
            fail(what + ": color must be finite and not negative");
        if (!std::isfinite(out.intensity) || out.intensity < 0.0f)
            fail(what + ": intensity must be finite and not negative");
        if (!std::isfinite(out.range) || out.range < 0.0f)
            fail(what + ": range must be finite and not negative");
        if (out.type == PunctualLight::Type::Spot &&
            !(out.inner_cone >= 0.0f && out.inner_cone < out.outer_cone &&
              out.outer_cone <= float(M_PI / 2) + 1e-6f))
            fail(what + ": the spot's cone angles must satisfy 0 <= inner < outer <= pi/2");
        out.position = glm::vec3(world[3]);
        const glm::vec3 forward = -glm::vec3(world[2]);
        if (!(glm::length(forward) > 0.0f) ||
            !std::isfinite(out.position.x + out.position.y + out.position.z))
            fail("node " + std::to_string(node) + " places " + what + " with a degenerate transform");
        out.direction = glm::normalize(forward);
        // The bake mode: the light's extras, else its node's.
        for (const tinygltf::Value* extras : {&l.extras, &model.nodes[size_t(node)].extras})
        {
            if (!extras->IsObject() || !extras->Has("hemi_bake_mode"))
                continue;
            const tinygltf::Value& v = extras->Get("hemi_bake_mode");
            if (!v.IsString() || !parse_light_mode(v.Get<std::string>(), out.mode))
                fail(what + ": extras.hemi_bake_mode must be \"baked\", \"mixed\" or \"realtime\"" +
                     (v.IsString() ? ", not \"" + v.Get<std::string>() + "\"" : ""));
            break;
        }
        scene.lights.push_back(out);
        lights_placed = true;
    }

    void check_extensions()
    {
        for (const std::string& ext : model.extensionsRequired)
        {
            if (kSupportedExtensions.count(ext) || appearance_only(ext))
                continue;
            if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression" ||
                ext == "KHR_meshopt_compression")
                fail("requires " + ext +
                     " (compressed geometry), which hemi cannot decode; re-export the scene "
                     "without mesh compression");
            fail("requires extension " + ext + ", which hemi does not support");
        }
        for (const std::string& ext : model.extensionsUsed)
            if (ext == "EXT_meshopt_compression" || ext == "KHR_meshopt_compression")
                warnings.add(ext, ext + " ignored: the uncompressed fallback buffers are read");
        if (!model.animations.empty())
            warnings.add("animations", "animations ignored: the scene is drawn in its rest pose (" +
                                           std::to_string(model.animations.size()) + " animation(s))");
    }

    void run()
    {
        check_extensions();
        image_of.assign(model.images.size(), -1);
        for (size_t i = 0; i < model.materials.size(); ++i)
            scene.materials.push_back(material(i));
        if (!model.scenes.empty())
        {
            const size_t s = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size()
                                 ? size_t(model.defaultScene)
                                 : 0;
            walk(model.scenes[s].nodes, "scene " + std::to_string(s));
        }
        else
            for (size_t i = 0; i < model.meshes.size(); ++i)
                add_mesh(int(i), glm::mat4(1.0f));
        if (scene.mesh.indices.empty())
            fail("the scene has no triangles" +
                 (skipped ? " (" + std::to_string(skipped) + " point or line primitive(s) skipped)"
                          : std::string()));
        if (scene.mesh.indices.size() > std::numeric_limits<uint32_t>::max())
            fail("more than 2^32 indices");
        if (any_uvs1)
        {
            for (const std::string& where : without_uvs1)
                warnings.add("TEXCOORD_1 missing",
                             where + " has no TEXCOORD_1 while others do: it reads (0, 0) there");
        }
        else
        {
            scene.mesh.uvs1.clear();
            for (size_t i = 0; i < scene.materials.size(); ++i)
                for (TextureRef* t : {&scene.materials[i].base_color, &scene.materials[i].normal,
                                      &scene.materials[i].emissive, &scene.materials[i].occlusion})
                    if (t->present() && t->texcoord == 1)
                    {
                        warnings.add("TEXCOORD_1 absent",
                                     "material " + std::to_string(i) +
                                         " reads TEXCOORD_1, which no primitive has: it reads "
                                         "TEXCOORD_0");
                        t->texcoord = 0;
                    }
        }
        if (!model.lights.empty() && !lights_placed)
            warnings.add("KHR_lights_punctual",
                         "KHR_lights_punctual: " + std::to_string(model.lights.size()) +
                             " light(s) that no node places: ignored");
        scene.warnings = warnings.lines();
        // What this reader builds must be what every consumer of a scene accepts.
        if (std::string p = surface_problem(scene.mesh, scene.materials, scene.images, scene.primitives);
            !p.empty())
            fail("internal error: " + p);
    }
};

// tinygltf hands every image's bytes to this loader: a data URI's decoded bytes (the URI itself is then
// dropped), an external file's bytes and a buffer view's. hemi keeps images encoded and reads external files
// and buffer views itself (with its own path rules and bounds checks), so only data URIs are captured here.
bool capture_data_uri(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*)
{
    if (image->uri.empty() && image->bufferView < 0 && bytes && size > 0)
    {
        image->image.assign(bytes, bytes + size);
        image->as_is = true;
    }
    return true;
}

// glTF 1.0 files parse as JSON but mean something else (objects keyed by id where 2.0 has arrays): refused
// with what to do about it. `binary`: the 12-byte .glb header's version; JSON: asset.version.
void refuse_gltf1(const std::string& file, const std::string& version)
{
    if (version.rfind("1", 0) == 0)
        throw FormatError(file + ": glTF " + version + " is not supported; re-export as glTF 2.0");
    if (!version.empty() && version.rfind("2", 0) != 0)
        throw FormatError(file + ": glTF version " + version + " is not supported (hemi reads glTF 2.0)");
}

std::string json_version(const std::filesystem::path& path)
{
    std::ifstream f(path, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (!j.is_object())
        return {};
    if (j.contains("asset") && j["asset"].is_object() && j["asset"].contains("version") &&
        j["asset"]["version"].is_string())
        return j["asset"]["version"].get<std::string>();
    // glTF 1.0 made "asset" optional; its top-level collections are objects keyed by id.
    for (const char* key : {"meshes", "accessors", "nodes", "buffers"})
        if (j.contains(key) && j[key].is_object())
            return "1.0";
    return {};
}

} // namespace

const char* light_mode_name(LightMode mode)
{
    switch (mode)
    {
    case LightMode::Baked:
        return "baked";
    case LightMode::Mixed:
        return "mixed";
    case LightMode::Realtime:
        return "realtime";
    }
    return "baked";
}

bool parse_light_mode(std::string_view name, LightMode& mode)
{
    for (const LightMode m : {LightMode::Baked, LightMode::Mixed, LightMode::Realtime})
        if (name == light_mode_name(m))
        {
            mode = m;
            return true;
        }
    return false;
}

GltfScene read_gltf(const std::filesystem::path& path)
{
    const std::string file = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        throw FormatError(file + ": no such file");
    // Binary or JSON by the content, not the extension.
    char header[12] = {};
    {
        std::ifstream f(path, std::ios::binary);
        f.read(header, sizeof header);
    }
    const bool binary = std::memcmp(header, "glTF", 4) == 0;
    if (binary)
    {
        uint32_t version;
        std::memcpy(&version, header + 4, 4);
        if (version == 1)
            throw FormatError(file + ": glTF 1.0 is not supported; re-export as glTF 2.0");
        if (version != 2)
            throw FormatError(file + ": binary glTF version " + std::to_string(version) +
                              " is not supported");
    }

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(capture_data_uri, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, file)
                           : loader.LoadASCIIFromFile(&model, &err, &warn, file);
    if (!binary)
        refuse_gltf1(file, ok ? model.asset.version : json_version(path));
    if (!ok)
    {
        std::string why = !err.empty() ? err : !warn.empty() ? warn : std::string("unknown error");
        while (!why.empty() && (why.back() == '\n' || why.back() == ' '))
            why.pop_back();
        throw FormatError(file + ": not a readable glTF file: " + why);
    }
    if (binary)
        refuse_gltf1(file, model.asset.version);

    Reader r{file, model, path.parent_path(), {}, {}, {}, -1, false, {}, 0};
    try
    {
        r.run();
    }
    catch (const std::bad_alloc&)
    {
        throw FormatError(file + ": out of memory: the file declares more data than fits");
    }
    catch (const std::length_error&)
    {
        throw FormatError(file + ": the file declares more data than fits");
    }
    return std::move(r.scene);
}

// ---- writing ----

namespace
{

// RFC 4648 base64 (tinygltf's encoder is not in its public header).
std::string base64(const std::vector<uint8_t>& in)
{
    static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((in.size() + 2) / 3 * 4);
    for (size_t i = 0; i < in.size(); i += 3)
    {
        const uint32_t rest = uint32_t(std::min<size_t>(3, in.size() - i));
        uint32_t v = uint32_t(in[i]) << 16;
        if (rest > 1)
            v |= uint32_t(in[i + 1]) << 8;
        if (rest > 2)
            v |= in[i + 2];
        out.push_back(digits[(v >> 18) & 63]);
        out.push_back(digits[(v >> 12) & 63]);
        out.push_back(rest > 1 ? digits[(v >> 6) & 63] : '=');
        out.push_back(rest > 2 ? digits[v & 63] : '=');
    }
    return out;
}

std::string geometry_problem(const Mesh& mesh)
{
    const size_t n = mesh.vertex_count();
    if (n == 0 || mesh.indices.empty() || mesh.indices.size() % 3)
        return "empty or non-triangle mesh";
    for (uint32_t i : mesh.indices)
        if (i >= n)
            return "index " + std::to_string(i) + " out of range (" + std::to_string(n) + " vertices)";
    for (size_t size : {mesh.normals.size(), mesh.tangents.size(), mesh.uvs.size(), mesh.uvs1.size()})
        if (size != 0 && size != n)
            return "an attribute has " + std::to_string(size) + " values for " + std::to_string(n) +
                   " vertices";
    return {};
}

} // namespace

void write_gltf(const std::filesystem::path& path, const Mesh& mesh, const std::string& base_color_uri,
                const std::string& normal_uri)
{
    if (std::string p = geometry_problem(mesh); !p.empty())
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": " + p);
    detail::GltfBuilder b;
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    std::vector<uint32_t> all(mesh.vertex_count());
    for (size_t v = 0; v < all.size(); ++v)
        all[v] = uint32_t(v);
    b.attributes(prim, mesh, all, false);
    prim.indices =
        b.accessor(mesh.indices.data(), mesh.indices.size() * 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                   TINYGLTF_TYPE_SCALAR, mesh.indices.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    tinygltf::Material material;
    material.name = "hemi";
    auto texture = [&](const std::string& uri)
    {
        tinygltf::Image image;
        image.uri = uri;
        b.m.images.push_back(image);
        tinygltf::Texture t;
        t.source = int(b.m.images.size() - 1);
        b.m.textures.push_back(t);
        return int(b.m.textures.size() - 1);
    };
    if (!base_color_uri.empty())
        material.pbrMetallicRoughness.baseColorTexture.index = texture(base_color_uri);
    if (!normal_uri.empty())
        material.normalTexture.index = texture(normal_uri);
    b.m.materials.push_back(material);
    prim.material = 0;
    tinygltf::Mesh gmesh;
    gmesh.primitives.push_back(prim);
    b.single_node(gmesh);
    b.write(path);
}

void write_gltf(const std::filesystem::path& path, const GltfScene& scene, ImageStorage storage)
{
    write_gltf(path, scene, std::vector<ImageStorage>(scene.images.size(), storage));
}

namespace detail
{
GltfBuilder scene_builder(const std::filesystem::path& path, const GltfScene& scene,
                          const std::vector<ImageStorage>& storage)
{
    const std::string cannot = "hemi: cannot write " + path.string() + ": ";
    if (std::string p = geometry_problem(scene.mesh); !p.empty())
        throw std::invalid_argument(cannot + p);
    if (std::string p = surface_problem(scene.mesh, scene.materials, scene.images, scene.primitives);
        !p.empty())
        throw std::invalid_argument(cannot + p);
    if (scene.primitives.empty())
        throw std::invalid_argument(cannot + "no primitives");
    if (storage.size() != scene.images.size())
        throw std::invalid_argument(cannot + std::to_string(storage.size()) + " image storages for " +
                                    std::to_string(scene.images.size()) + " images");
    detail::GltfBuilder b;

    // Images, and the external files beside the glTF (written first: a glTF never refers to a missing file).
    const std::filesystem::path folder = path.parent_path();
    std::set<std::string> names;
    for (size_t i = 0; i < scene.images.size(); ++i)
    {
        const EncodedImage& image = scene.images[i];
        const std::string ext = image.mime_type == "image/png" ? ".png" : ".jpg";
        tinygltf::Image out;
        switch (storage[i])
        {
        case ImageStorage::BufferView:
            out.bufferView = b.view(image.bytes.data(), image.bytes.size(), 0);
            out.mimeType = image.mime_type;
            break;
        case ImageStorage::DataUri:
            out.uri = "data:" + image.mime_type + ";base64," + base64(image.bytes);
            break;
        case ImageStorage::External:
        {
            // The image's own name when it is a plain file name of the right type, else one made up.
            const std::filesystem::path own(image.name);
            std::string name = own.filename().string();
            const std::string own_ext = own.extension().string();
            const bool usable = !name.empty() && name == image.name && name != "." && name != ".." &&
                                (own_ext == ext || (ext == ".jpg" && own_ext == ".jpeg"));
            if (!usable || names.count(name))
                name = path.stem().string() + "_image" + std::to_string(i) + ext;
            names.insert(name);
            write_atomically(folder / name,
                             [&](const std::filesystem::path& tmp)
                             {
                                 std::ofstream f(tmp, std::ios::binary);
                                 f.write(reinterpret_cast<const char*>(image.bytes.data()),
                                         std::streamsize(image.bytes.size()));
                                 f.close();
                                 if (f.fail())
                                     throw FormatError((folder / name).string() +
                                                       ": writing the image failed");
                             });
            out.uri = percent_encode(name);
            break;
        }
        }
        b.m.images.push_back(out);
    }

    // Samplers and textures, one per distinct (image, sampler).
    std::vector<TextureSampler> samplers;
    std::map<std::pair<int, size_t>, int> textures;
    bool transforms = false;
    auto info = [&](const TextureRef& ref, int& index, int& texcoord, tinygltf::ExtensionMap& extensions)
    {
        if (!ref.present())
            return;
        size_t s = std::find(samplers.begin(), samplers.end(), ref.sampler) - samplers.begin();
        if (s == samplers.size())
        {
            samplers.push_back(ref.sampler);
            tinygltf::Sampler out;
            auto wrap = [](Wrap w)
            {
                return w == Wrap::ClampToEdge      ? TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE
                       : w == Wrap::MirroredRepeat ? TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT
                                                   : TINYGLTF_TEXTURE_WRAP_REPEAT;
            };
            out.wrapS = wrap(ref.sampler.wrap_s);
            out.wrapT = wrap(ref.sampler.wrap_t);
            out.magFilter = ref.sampler.mag_filter == Filter::Nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST
                                                                      : TINYGLTF_TEXTURE_FILTER_LINEAR;
            const bool nearest = ref.sampler.min_filter == Filter::Nearest;
            out.minFilter = ref.sampler.mipmaps ? (nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR
                                                           : TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR)
                                                : (nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST
                                                           : TINYGLTF_TEXTURE_FILTER_LINEAR);
            b.m.samplers.push_back(out);
        }
        auto [it, added] = textures.try_emplace({ref.image, s}, int(b.m.textures.size()));
        if (added)
        {
            tinygltf::Texture t;
            t.source = ref.image;
            t.sampler = int(s);
            b.m.textures.push_back(t);
        }
        index = it->second;
        texcoord = int(ref.texcoord);
        if (ref.offset != glm::vec2(0.0f) || ref.scale != glm::vec2(1.0f) || ref.rotation != 0.0f)
        {
            tinygltf::Value::Object t;
            t["offset"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(double(ref.offset.x)),
                                                                 tinygltf::Value(double(ref.offset.y))});
            t["scale"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(double(ref.scale.x)),
                                                                tinygltf::Value(double(ref.scale.y))});
            t["rotation"] = tinygltf::Value(double(ref.rotation));
            extensions["KHR_texture_transform"] = tinygltf::Value(t);
            transforms = true;
        }
    };
    for (const Material& mat : scene.materials)
    {
        tinygltf::Material out;
        out.name = mat.name;
        auto& pbr = out.pbrMetallicRoughness;
        pbr.baseColorFactor = {mat.base_color_factor.r, mat.base_color_factor.g, mat.base_color_factor.b,
                               mat.base_color_factor.a};
        pbr.metallicFactor = 0.0; // hemi's techniques are diffuse: what other viewers should show too
        pbr.roughnessFactor = 1.0;
        info(mat.base_color, pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
             pbr.baseColorTexture.extensions);
        info(mat.normal, out.normalTexture.index, out.normalTexture.texCoord, out.normalTexture.extensions);
        out.normalTexture.scale = mat.normal_scale;
        info(mat.emissive, out.emissiveTexture.index, out.emissiveTexture.texCoord,
             out.emissiveTexture.extensions);
        info(mat.occlusion, out.occlusionTexture.index, out.occlusionTexture.texCoord,
             out.occlusionTexture.extensions);
        out.occlusionTexture.strength = mat.occlusion_strength;
        out.emissiveFactor = {mat.emissive_factor.r, mat.emissive_factor.g, mat.emissive_factor.b};
        out.doubleSided = mat.double_sided;
        if (!mat.technique.empty())
        {
            tinygltf::Value::Object extras;
            extras["hemi_technique"] = tinygltf::Value(mat.technique);
            out.extras = tinygltf::Value(extras);
        }
        if (mat.alpha_mode != io::AlphaMode::Opaque)
        {
            out.alphaMode = mat.alpha_mode == io::AlphaMode::Mask ? "MASK" : "BLEND";
            out.alphaCutoff = mat.alpha_cutoff;
        }
        b.m.materials.push_back(out);
    }
    if (transforms)
        b.m.extensionsUsed.push_back("KHR_texture_transform");

    // One glTF primitive per range, with the vertices it uses (ascending: a mesh laid out primitive by
    // primitive reads back as it was).
    const Mesh& mesh = scene.mesh;
    tinygltf::Mesh gmesh;
    std::vector<uint32_t> local(mesh.vertex_count());
    for (const Primitive& p : scene.primitives)
    {
        std::vector<uint32_t> used(mesh.indices.begin() + p.first_index,
                                   mesh.indices.begin() + p.first_index + p.index_count);
        std::sort(used.begin(), used.end());
        used.erase(std::unique(used.begin(), used.end()), used.end());
        for (size_t k = 0; k < used.size(); ++k)
            local[used[k]] = uint32_t(k);
        std::vector<uint32_t> indices(p.index_count);
        for (uint32_t k = 0; k < p.index_count; ++k)
            indices[k] = local[mesh.indices[p.first_index + k]];
        bool uvs1 = false;
        if (!mesh.uvs1.empty())
            for (uint32_t v : used)
                uvs1 |= mesh.uvs1[v] != glm::vec2(0.0f);
        tinygltf::Primitive prim;
        prim.mode = TINYGLTF_MODE_TRIANGLES;
        prim.material = int(p.material);
        b.attributes(prim, mesh, used, uvs1);
        prim.indices = b.accessor(indices.data(), indices.size() * 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                  TINYGLTF_TYPE_SCALAR, indices.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
        gmesh.primitives.push_back(prim);
    }
    b.single_node(gmesh);
    // The light probes placed by hand, as empties named as read_gltf finds them.
    for (size_t i = 0; i < scene.light_probes.size(); ++i)
    {
        const glm::vec3& at = scene.light_probes[i];
        if (!std::isfinite(at.x + at.y + at.z))
            throw std::invalid_argument("hemi: cannot write " + path.string() + ": light probe " +
                                        std::to_string(i) + " is not at a finite point");
        tinygltf::Node node;
        node.name = std::string(kLightProbeNodePrefix) + (i ? "." + std::to_string(i) : "");
        node.translation = {double(at.x), double(at.y), double(at.z)};
        b.m.scenes[0].nodes.push_back(int(b.m.nodes.size()));
        b.m.nodes.push_back(node);
    }
    return b;
}
} // namespace detail

void write_gltf(const std::filesystem::path& path, const GltfScene& scene,
                const std::vector<ImageStorage>& storage)
{
    detail::scene_builder(path, scene, storage).write(path);
}

} // namespace hemi::io
