// The lightmap asset in the .hemi container (lightmap_asset.h).
#include <hemi/io/asset.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/basis.h>

#include "scene_sections.h"

#include <glm/gtc/packing.hpp>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::io
{
namespace
{

constexpr uint32_t kLightmapLayoutVersion = 1;

struct Info
{
    uint32_t layout, width, height, rays;
    uint64_t seed;
    uint32_t bounces, covered;
};
static_assert(sizeof(Info) == 32);

// What an output's K must be: 1 for "plain", 3 for "rnm", the basis's size for a name of math::bases();
// 0 for a name that is none of them.
uint32_t expected_k(const std::string& name)
{
    if (name == "plain")
        return 1;
    if (name == "rnm")
        return 3;
    for (const math::BasisDesc& b : math::bases())
        if (b.name == name)
            return uint32_t(b.size);
    return 0;
}

std::string problem(const LightmapAsset& a)
{
    if (std::string p = mesh_problem(a.mesh, MeshNeeds::Frames); !p.empty())
        return p;
    if (a.mesh.uvs1.size() != a.mesh.vertex_count())
        return "the mesh has no lightmap UVs (mesh.uvs1)";
    if (std::string p = surface_problem(a.mesh, a.materials, a.images, a.primitives); !p.empty())
        return p;
    if (a.width == 0 || a.height == 0 || a.width > 16384 || a.height > 16384)
        return "atlas size " + std::to_string(a.width) + "x" + std::to_string(a.height) + " is not in [1, 16384]";
    if (a.outputs.empty())
        return "no outputs";
    for (const LightmapOutput& o : a.outputs)
    {
        const uint32_t k = expected_k(o.name);
        if (k == 0)
            return "unknown output '" + o.name + "'";
        if (o.k != k)
            return "output '" + o.name + "' has K = " + std::to_string(o.k) + ", it needs " + std::to_string(k);
        const size_t expected = size_t(k) * a.width * a.height * 3;
        if (o.maps.size() != expected)
            return "output '" + o.name + "' holds " + std::to_string(o.maps.size()) + " values, expected " +
                   std::to_string(expected);
        for (float v : o.maps)
            if (!std::isfinite(v) || std::abs(v) > 65504.0f)
                return "output '" + o.name + "' holds a value that is not finite or does not fit a half float";
    }
    return {};
}

} // namespace

const LightmapOutput& LightmapAsset::output(const std::string& name) const
{
    std::string known;
    for (const LightmapOutput& o : outputs)
    {
        if (o.name == name)
            return o;
        known += (known.empty() ? "" : ", ") + o.name;
    }
    throw std::invalid_argument("the lightmap asset has no output '" + name + "' (it has: " + known + ")");
}

void write_lightmap_asset(const std::filesystem::path& path, const LightmapAsset& a)
{
    if (std::string p = problem(a); !p.empty())
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": " + p);
    AssetWriter w;
    const Info info{kLightmapLayoutVersion, a.width, a.height, a.rays, a.seed, a.bounces, a.covered_texels};
    w.add("lightmap.info", std::as_bytes(std::span<const Info>(&info, 1)));
    write_scene_sections(w, a.mesh, a.materials, a.images, a.primitives);
    for (const LightmapOutput& o : a.outputs)
    {
        std::vector<uint16_t> halves(o.maps.size() + 2);
        std::memcpy(halves.data(), &o.k, 4);
        for (size_t i = 0; i < o.maps.size(); ++i)
            halves[i + 2] = glm::packHalf1x16(o.maps[i]);
        w.add("L." + o.name, std::as_bytes(std::span<const uint16_t>(halves)));
    }
    w.write(path);
}

LightmapAsset read_lightmap_asset(const std::filesystem::path& path)
{
    const AssetReader r(path);
    const std::string file = path.string();
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(file + ": " + what); };
    if (!r.has("lightmap.info"))
        throw fail(r.has("prt.info") ? "a PRT asset, not a lightmap asset" : "not a lightmap asset (no lightmap.info)");
    const std::span<const std::byte> info_bytes = r.section("lightmap.info");
    if (info_bytes.size() != sizeof(Info))
        throw fail("lightmap.info has " + std::to_string(info_bytes.size()) + " bytes, expected " +
                   std::to_string(sizeof(Info)));
    Info info;
    std::memcpy(&info, info_bytes.data(), sizeof info);
    if (info.layout != kLightmapLayoutVersion)
        throw fail("lightmap layout version " + std::to_string(info.layout) + " is not supported (this hemi reads " +
                   std::to_string(kLightmapLayoutVersion) + ")");
    if (info.width == 0 || info.height == 0 || info.width > 16384 || info.height > 16384)
        throw fail("lightmap.info: atlas size " + std::to_string(info.width) + "x" + std::to_string(info.height) +
                   " is not in [1, 16384]");
    LightmapAsset a;
    a.width = info.width;
    a.height = info.height;
    a.rays = info.rays;
    a.seed = info.seed;
    a.bounces = info.bounces;
    a.covered_texels = info.covered;
    read_scene_sections(r, file, a.mesh, a.materials, a.images, a.primitives);
    const size_t texels = size_t(a.width) * a.height;
    for (const std::string& section : r.names())
    {
        if (section.rfind("L.", 0) != 0)
            continue;
        LightmapOutput o;
        o.name = section.substr(2);
        const std::span<const std::byte> b = r.section(section);
        if (b.size() < 4)
            throw fail(section + " is too short");
        std::memcpy(&o.k, b.data(), 4);
        const uint32_t k = expected_k(o.name);
        if (k == 0)
            throw fail("unknown output '" + o.name + "'");
        if (o.k != k)
            throw fail(section + ": K = " + std::to_string(o.k) + ", the output needs " + std::to_string(k));
        const uint64_t expected = 4 + uint64_t(k) * texels * 3 * 2;
        if (b.size() != expected)
            throw fail(section + " has " + std::to_string(b.size()) + " bytes, a " + std::to_string(a.width) + "x" +
                       std::to_string(a.height) + " atlas of K = " + std::to_string(k) + " needs " +
                       std::to_string(expected));
        o.maps.resize(size_t(k) * texels * 3);
        for (size_t i = 0; i < o.maps.size(); ++i)
        {
            uint16_t h;
            std::memcpy(&h, b.data() + 4 + 2 * i, 2);
            o.maps[i] = glm::unpackHalf1x16(h);
        }
        a.outputs.push_back(std::move(o));
    }
    if (std::string p = problem(a); !p.empty())
        throw fail(p);
    return a;
}

std::string asset_kind(const std::filesystem::path& path)
{
    const AssetReader r(path);
    if (r.has("lightmap.info"))
        return "lightmap";
    if (r.has("prt.info"))
        return "prt";
    throw FormatError(path.string() + ": a hemi container, but neither a PRT nor a lightmap asset");
}

} // namespace hemi::io
