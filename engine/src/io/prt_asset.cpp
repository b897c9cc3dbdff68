#include <hemi/io/asset.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/basis.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>
#include <string>

namespace hemi::io
{

const PrtTechnique& PrtAsset::technique(const std::string& name) const
{
    std::string known;
    for (const PrtTechnique& t : techniques)
    {
        if (t.name == name)
            return t;
        known += (known.empty() ? "" : ", ") + t.name;
    }
    throw std::invalid_argument("hemi: the asset has no technique '" + name + "' (it has: " + known + ")");
}

namespace
{

struct Info
{
    uint32_t layout, vertices, order, transfer_kind, bounces, rays;
    uint64_t seed;
    float albedo;
    uint32_t reserved;
};
static_assert(sizeof(Info) == 40);

template <typename T>
bool finite(const std::vector<T>& v)
{
    for (const T& x : v)
        for (int c = 0; c < int(sizeof(T) / sizeof(float)); ++c)
            if (!std::isfinite(reinterpret_cast<const float*>(&x)[c]))
                return false;
    return true;
}

// The problem with an asset, or an empty string.
std::string problem(const PrtAsset& a)
{
    const size_t n = a.mesh.vertex_count();
    if (std::string p = mesh_problem(a.mesh, MeshNeeds::Frames); !p.empty())
        return p;
    if (std::string p = surface_problem(a.mesh, a.materials, a.images, a.primitives); !p.empty())
        return p;
    if (a.primitives.empty())
        return "no primitives (the asset's surfaces: at least one material and primitive)";
    if (a.order < 3 || a.order > 6)
        return "lighting order " + std::to_string(a.order) + " is not in [3, 6]";
    if (a.transfer_kind > 2)
        return "unknown transfer kind " + std::to_string(a.transfer_kind);
    if (a.techniques.empty())
        return "no techniques";
    const size_t l = a.l();
    for (const PrtTechnique& t : a.techniques)
    {
        const std::string where = "technique '" + t.name + "': ";
        int k = 0;
        try
        {
            k = math::technique(t.name).size;
        }
        catch (const std::invalid_argument&)
        {
            return "unknown technique '" + t.name + "'";
        }
        if (t.name.size() > 24)
            return where + "name too long";
        if (uint32_t(k) != t.k)
            return where + "K = " + std::to_string(t.k) + ", the technique has " + std::to_string(k);
        const size_t d = size_t(k) * l;
        if (t.matrices.empty() && !t.cpca)
            return where + "neither matrices nor CPCA data";
        if (!t.matrices.empty() && t.matrices.size() != n * d)
            return where + std::to_string(t.matrices.size()) + " matrix values, expected " + std::to_string(n * d);
        if (!finite(t.matrices))
            return where + "non-finite matrix value";
        if (t.cpca)
        {
            const PrtCpca& c = *t.cpca;
            if (c.clusters == 0 || c.vectors == 0 || c.vectors > 1024 || c.clusters > n)
                return where + "CPCA shape " + std::to_string(c.clusters) + "x" + std::to_string(c.vectors) +
                       " is not valid for " + std::to_string(n) + " vertices";
            if (c.means.size() != c.clusters * d || c.basis.size() != size_t(c.clusters) * c.vectors * d ||
                c.cluster.size() != n || c.weights.size() != n * c.vectors)
                return where + "CPCA array sizes do not match its shape";
            for (uint32_t id : c.cluster)
                if (id >= c.clusters)
                    return where + "CPCA cluster " + std::to_string(id) + " out of range";
            if (!finite(c.means) || !finite(c.basis) || !finite(c.weights) || !std::isfinite(c.rms_error))
                return where + "non-finite CPCA value";
        }
    }
    return {};
}

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

std::string scene_json(const PrtAsset& a)
{
    json materials = json::array(), images = json::array();
    for (const Material& m : a.materials)
    {
        json j = {
            {"name", m.name},
            {"base_color_factor",
             {m.base_color_factor.r, m.base_color_factor.g, m.base_color_factor.b, m.base_color_factor.a}},
            {"normal_scale", m.normal_scale},
            {"emissive_factor", {m.emissive_factor.r, m.emissive_factor.g, m.emissive_factor.b}},
            {"double_sided", m.double_sided}};
        for (const auto& [ref, key] : {std::pair{&m.base_color, "base_color"}, std::pair{&m.normal, "normal"},
                                       std::pair{&m.emissive, "emissive"}})
            if (ref->present())
                j[key] = texture_json(*ref);
        materials.push_back(std::move(j));
    }
    for (const EncodedImage& im : a.images)
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
    std::vector<uint64_t> read(std::span<const std::byte> bytes, PrtAsset& a) const
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
                  std::pair{&out.emissive, "emissive"}})
                if (m.contains(key))
                    *ref = texture(m[key], where + " " + key);
            a.materials.push_back(std::move(out));
        }
        std::vector<uint64_t> sizes;
        for (size_t i = 0; i < images.size(); ++i)
        {
            const std::string where = "image " + std::to_string(i);
            EncodedImage im;
            im.name = string(images[i], "name", where);
            im.mime_type = string(images[i], "mime_type", where);
            sizes.push_back(uint64_t(integer(images[i], "bytes", 1, INT64_MAX, where)));
            a.images.push_back(std::move(im));
        }
        return sizes;
    }
};

template <typename T>
void add(AssetWriter& w, const std::string& name, const std::vector<T>& v)
{
    w.add_array(name, std::span<const T>(v));
}

template <typename T>
void append(std::vector<std::byte>& out, const T* data, size_t count)
{
    const auto* b = reinterpret_cast<const std::byte*>(data);
    out.insert(out.end(), b, b + count * sizeof(T));
}

} // namespace

void write_prt_asset(const std::filesystem::path& path, const PrtAsset& a)
{
    if (std::string p = problem(a); !p.empty())
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": " + p);
    AssetWriter w;
    Info info{kPrtLayoutVersion, uint32_t(a.mesh.vertex_count()), a.order, a.transfer_kind, a.bounces,
              a.rays, a.seed, a.albedo, 0};
    w.add("prt.info", std::as_bytes(std::span<const Info>(&info, 1)));
    add(w, "mesh.positions", a.mesh.positions);
    add(w, "mesh.normals", a.mesh.normals);
    add(w, "mesh.tangents", a.mesh.tangents);
    add(w, "mesh.uvs", a.mesh.uvs);
    add(w, "mesh.indices", a.mesh.indices);
    if (!a.mesh.uvs1.empty())
        add(w, "mesh.uvs1", a.mesh.uvs1);
    const std::string materials = scene_json(a);
    w.add("scene.materials", std::as_bytes(std::span<const char>(materials)));
    std::vector<uint32_t> primitives;
    for (const Primitive& p : a.primitives)
        primitives.insert(primitives.end(), {p.first_index, p.index_count, p.material});
    add(w, "scene.primitives", primitives);
    for (size_t i = 0; i < a.images.size(); ++i)
        w.add("image." + std::to_string(i), std::as_bytes(std::span<const uint8_t>(a.images[i].bytes)));
    for (const PrtTechnique& t : a.techniques)
    {
        if (!t.matrices.empty())
            add(w, "T." + t.name, t.matrices);
        if (t.cpca)
        {
            const PrtCpca& c = *t.cpca;
            std::vector<std::byte> bytes;
            const uint32_t shape[2] = {c.clusters, c.vectors};
            append(bytes, shape, 2);
            append(bytes, &c.rms_error, 1);
            append(bytes, c.means.data(), c.means.size());
            append(bytes, c.basis.data(), c.basis.size());
            append(bytes, c.cluster.data(), c.cluster.size());
            append(bytes, c.weights.data(), c.weights.size());
            w.add("C." + t.name, bytes);
        }
    }
    w.write(path);
}

PrtAsset read_prt_asset(const std::filesystem::path& path)
{
    const AssetReader r(path);
    const std::string file = path.string();
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(file + ": " + what); };

    std::span<const std::byte> info_bytes = r.section("prt.info");
    if (info_bytes.size() != sizeof(Info))
        throw fail("prt.info has " + std::to_string(info_bytes.size()) + " bytes, expected " +
                   std::to_string(sizeof(Info)));
    Info info;
    std::memcpy(&info, info_bytes.data(), sizeof info);
    if (info.layout == 1)
        throw fail(
            "written by an older hemi (PRT layout 1, which referenced its textures by path); re-bake it "
            "with this hemi's hemi-bake prt");
    if (info.layout != kPrtLayoutVersion)
        throw fail("PRT layout version " + std::to_string(info.layout) + " is not supported (this hemi reads " +
                   std::to_string(kPrtLayoutVersion) + ")");
    // The numbers every size below is computed from, checked before any arithmetic uses them.
    if (info.order < 3 || info.order > 6)
        throw fail("prt.info: lighting order " + std::to_string(info.order) + " is not in [3, 6]");
    if (info.vertices == 0)
        throw fail("prt.info: no vertices");
    PrtAsset a;
    a.order = info.order;
    a.transfer_kind = info.transfer_kind;
    a.bounces = info.bounces;
    a.rays = info.rays;
    a.seed = info.seed;
    a.albedo = info.albedo;
    a.mesh.positions = r.array<glm::vec3>("mesh.positions");
    a.mesh.normals = r.array<glm::vec3>("mesh.normals");
    a.mesh.tangents = r.array<glm::vec4>("mesh.tangents");
    a.mesh.uvs = r.array<glm::vec2>("mesh.uvs");
    a.mesh.indices = r.array<uint32_t>("mesh.indices");
    if (a.mesh.vertex_count() != info.vertices)
        throw fail("prt.info says " + std::to_string(info.vertices) + " vertices, mesh.positions holds " +
                   std::to_string(a.mesh.vertex_count()));
    if (r.has("mesh.uvs1"))
        a.mesh.uvs1 = r.array<glm::vec2>("mesh.uvs1");

    // The surfaces: materials and image metadata, primitives, then each image's bytes.
    const std::vector<uint64_t> image_sizes = SceneJson{file}.read(r.section("scene.materials"), a);
    const std::vector<uint32_t> primitives = r.array<uint32_t>("scene.primitives");
    if (primitives.size() % 3 != 0)
        throw fail("scene.primitives holds " + std::to_string(primitives.size()) +
                   " values, not (first, count, material) triples");
    for (size_t i = 0; i < primitives.size(); i += 3)
        a.primitives.push_back({primitives[i], primitives[i + 1], primitives[i + 2]});
    for (size_t i = 0; i < a.images.size(); ++i)
    {
        const std::string name = "image." + std::to_string(i);
        const std::span<const std::byte> b = r.section(name);
        if (b.size() != image_sizes[i])
            throw fail(name + " holds " + std::to_string(b.size()) + " bytes, scene.materials says " +
                       std::to_string(image_sizes[i]));
        const auto* p = reinterpret_cast<const uint8_t*>(b.data());
        a.images[i].bytes.assign(p, p + b.size());
    }
    std::set<std::string> listed;
    for (size_t i = 0; i < a.images.size(); ++i)
        listed.insert("image." + std::to_string(i));
    for (const std::string& section : r.names())
        if (section.rfind("image.", 0) == 0 && !listed.count(section))
            throw fail("section '" + section + "' is not one of the " + std::to_string(a.images.size()) +
                       " images scene.materials lists");

    const size_t n = info.vertices, l = size_t(info.order) * info.order;
    std::vector<std::string> names;
    for (const std::string& section : r.names())
        if ((section.rfind("T.", 0) == 0 || section.rfind("C.", 0) == 0) &&
            std::find(names.begin(), names.end(), section.substr(2)) == names.end())
            names.push_back(section.substr(2));
    for (const std::string& name : names)
    {
        const std::string dense = "T." + name, compressed = "C." + name;
        PrtTechnique t;
        t.name = name;
        try
        {
            t.k = uint32_t(math::technique(name).size);
        }
        catch (const std::invalid_argument&)
        {
            throw fail("unknown technique '" + name + "'");
        }
        if (r.has(dense))
            t.matrices = r.array<float>(dense);
        if (r.has(compressed))
        {
            std::span<const std::byte> b = r.section(compressed);
            PrtCpca c;
            if (b.size() < 12)
                throw fail(compressed + " is too short");
            uint32_t shape[2];
            std::memcpy(shape, b.data(), 8);
            std::memcpy(&c.rms_error, b.data() + 8, 4);
            c.clusters = shape[0];
            c.vectors = shape[1];
            const size_t d = size_t(t.k) * l; // at most 9 x 36
            if (c.clusters == 0 || c.clusters > n || c.vectors == 0 || c.vectors > 1024)
                throw fail(compressed + ": CPCA shape " + std::to_string(c.clusters) + "x" +
                           std::to_string(c.vectors) + " is not valid for " + std::to_string(n) + " vertices");
            // Every factor is bounded now (n < 2^32, C <= n, V <= 1024, d <= 324): no overflow in 64 bits.
            const uint64_t expected = 12 + 4 * (uint64_t(c.clusters) * d + uint64_t(c.clusters) * c.vectors * d +
                                                n + n * uint64_t(c.vectors));
            if (b.size() != expected)
                throw fail(compressed + " has " + std::to_string(b.size()) + " bytes, its shape " +
                           std::to_string(c.clusters) + "x" + std::to_string(c.vectors) + " needs " +
                           std::to_string(expected));
            const std::byte* p = b.data() + 12;
            auto take = [&](auto& v, size_t count) {
                v.resize(count);
                std::memcpy(v.data(), p, count * 4);
                p += count * 4;
            };
            take(c.means, c.clusters * d);
            take(c.basis, size_t(c.clusters) * c.vectors * d);
            take(c.cluster, n);
            take(c.weights, n * c.vectors);
            t.cpca = std::move(c);
        }
        a.techniques.push_back(std::move(t));
    }
    if (std::string p = problem(a); !p.empty())
        throw fail(p);
    return a;
}

} // namespace hemi::io
