#include <hemi/io/asset.h>
#include <hemi/io/image.h>
#include <hemi/io/prt_asset.h>
#include <hemi/math/basis.h>

#include "scene_sections.h"

#include <algorithm>
#include <cmath>
#include <cstring>
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

template <typename T> bool finite(const std::vector<T>& v)
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
            return where + std::to_string(t.matrices.size()) + " matrix values, expected " +
                   std::to_string(n * d);
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

template <typename T> void add(AssetWriter& w, const std::string& name, const std::vector<T>& v)
{
    w.add_array(name, std::span<const T>(v));
}

template <typename T> void append(std::vector<std::byte>& out, const T* data, size_t count)
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
    Info info{kPrtLayoutVersion,
              uint32_t(a.mesh.vertex_count()),
              a.order,
              a.transfer_kind,
              a.bounces,
              a.rays,
              a.seed,
              a.albedo,
              0};
    w.add("prt.info", std::as_bytes(std::span<const Info>(&info, 1)));
    write_scene_sections(w, a.mesh, a.materials, a.images, a.primitives);
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

namespace
{
PrtAsset read_prt_asset_from(const AssetReader& r)
{
    const std::string file = r.name();
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
        throw fail("PRT layout version " + std::to_string(info.layout) +
                   " is not supported (this hemi reads " + std::to_string(kPrtLayoutVersion) + ")");
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
    read_scene_sections(r, file, a.mesh, a.materials, a.images, a.primitives);
    if (a.mesh.vertex_count() != info.vertices)
        throw fail("prt.info says " + std::to_string(info.vertices) + " vertices, mesh.positions holds " +
                   std::to_string(a.mesh.vertex_count()));

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
                           std::to_string(c.vectors) + " is not valid for " + std::to_string(n) +
                           " vertices");
            // Every factor is bounded now (n < 2^32, C <= n, V <= 1024, d <= 324): no overflow in 64 bits.
            const uint64_t expected =
                12 + 4 * (uint64_t(c.clusters) * d + uint64_t(c.clusters) * c.vectors * d + n +
                          n * uint64_t(c.vectors));
            if (b.size() != expected)
                throw fail(compressed + " has " + std::to_string(b.size()) + " bytes, its shape " +
                           std::to_string(c.clusters) + "x" + std::to_string(c.vectors) + " needs " +
                           std::to_string(expected));
            const std::byte* p = b.data() + 12;
            auto take = [&](auto& v, size_t count)
            {
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
} // namespace

PrtAsset read_prt_asset(const std::filesystem::path& path)
{
    return read_prt_asset_from(AssetReader(path));
}

PrtAsset read_prt_asset(std::span<const std::byte> bytes, const std::string& name)
{
    return read_prt_asset_from(AssetReader(bytes, name));
}

} // namespace hemi::io
