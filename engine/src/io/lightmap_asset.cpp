// The lightmap asset in the .hemi container (lightmap_asset.h).
#include <hemi/io/asset.h>
#include <hemi/io/half_scale.h>
#include <hemi/io/image.h>
#include <hemi/io/lightmap_asset.h>
#include <hemi/math/basis.h>

#include "scene_sections.h"

#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>

namespace hemi::io
{
namespace
{

// Layout 3 stores each output's kept 8 x 8 blocks (io/block_maps.h) as halves with a power-of-two scale
// (io/half_scale.h); layout 2 (read, not written) the same blocks without a scale; layout 1 (read) the dense
// atlas. Layout 4 is layout 3 with mixed lights: written only for an asset with a shadowmask, so that a hemi
// that knows nothing of mixed lights refuses it instead of drawing them without their direct light.
constexpr uint32_t kLightmapLayoutVersion = 4;

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

static_assert(sizeof(std::array<glm::vec3, 9>) == 108, "a probe is 27 packed floats");

struct ProbeHeader
{
    uint32_t nx, ny, nz, zero;
    float lo[3], hi[3];
};
static_assert(sizeof(ProbeHeader) == 40);

// A light's record in lightmap.lights, before its name.
struct LightRecord
{
    uint32_t type, mode;
    int32_t channel;
    float color[3], intensity, range, inner_cone, outer_cone, position[3], direction[3], angular_diameter;
    uint32_t name_length;
};
static_assert(sizeof(LightRecord) == 72);

bool finite3(const glm::vec3& v)
{
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string output_problem(const LightmapOutput& o, uint32_t width, uint32_t height)
{
    const uint32_t k = expected_k(o.name);
    if (k == 0)
        return "unknown output '" + o.name + "'";
    if (o.k != k)
        return "output '" + o.name + "' has K = " + std::to_string(o.k) + ", it needs " + std::to_string(k);
    if (o.maps.k != k || o.maps.width() != width || o.maps.height() != height)
        return "output '" + o.name + "' holds " + std::to_string(o.maps.k) + " maps of " +
               std::to_string(o.maps.width()) + "x" + std::to_string(o.maps.height()) + ", expected " +
               std::to_string(k) + " of the atlas's " + std::to_string(width) + "x" + std::to_string(height);
    const size_t expected = o.maps.grid.slots() * k * 3;
    if (o.maps.values.size() != expected)
        return "output '" + o.name + "' holds " + std::to_string(o.maps.values.size()) +
               " values, its blocks need " + std::to_string(expected);
    for (float v : o.maps.values)
        if (!std::isfinite(v))
            return "output '" + o.name + "' holds a value that is not finite";
    return {};
}

// `shadowmask_to_come`: mixed lights may have no shadowmask in the asset (LightmapAssetWriter's, which may be
// given it by set_shadowmask).
std::string lights_problem(const LightmapAsset& a, bool shadowmask_to_come = false)
{
    int channels = 0;
    for (const LightmapLight& l : a.lights)
    {
        const PunctualLight& p = l.light;
        const std::string what = "light '" + p.name + "'";
        if (int(p.type) < 0 || int(p.type) > 2 || uint32_t(p.mode) > 2)
            return what + " has an unknown type or bake mode";
        if (!finite3(p.color) || !finite3(p.position) || !finite3(p.direction) ||
            !std::isfinite(p.intensity) || !std::isfinite(p.range) || !std::isfinite(p.inner_cone) ||
            !std::isfinite(p.outer_cone) || !std::isfinite(l.angular_diameter_degrees))
            return what + " holds a value that is not finite";
        if (p.color.r < 0.0f || p.color.g < 0.0f || p.color.b < 0.0f || p.intensity < 0.0f ||
            p.range < 0.0f || !(l.angular_diameter_degrees >= 0.0f && l.angular_diameter_degrees < 90.0f))
            return what + " has a negative colour, intensity or range, or a disc outside [0, 90) degrees";
        if (std::abs(glm::length(p.direction) - 1.0f) > 1e-3f)
            return what + "'s direction is not a unit vector";
        if (p.type == PunctualLight::Type::Spot &&
            !(p.inner_cone >= 0.0f && p.inner_cone < p.outer_cone && p.outer_cone <= float(M_PI / 2) + 1e-6f))
            return what + "'s cone angles do not satisfy 0 <= inner < outer <= pi/2";
        if (p.mode == LightMode::Mixed ? l.channel < 0 || l.channel > 3 : l.channel != -1)
            return what + " (" + light_mode_name(p.mode) + ") has shadowmask channel " +
                   std::to_string(l.channel);
        channels += p.mode == LightMode::Mixed;
    }
    const BlockMaps& m = a.shadowmask;
    if ((channels == 0 || shadowmask_to_come) && m.k == 0)
        return {};
    if (channels == 0 || m.k != 4)
        return channels == 0 ? "a shadowmask without mixed lights"
                             : "mixed lights without a shadowmask of 4 channels";
    if (m.width() != a.width || m.height() != a.height || m.values.size() != m.grid.slots() * 4 * 3)
        return "the shadowmask does not match the " + std::to_string(a.width) + "x" +
               std::to_string(a.height) + " atlas";
    for (float v : m.values)
        if (!(v >= 0.0f && v <= 1.0f))
            return "the shadowmask holds a value outside [0, 1]";
    return {};
}

// Everything but the outputs (LightmapAssetWriter's part), then the outputs when `outputs` says so.
std::string problem(const LightmapAsset& a, bool outputs = true)
{
    if (std::string p = mesh_problem(a.mesh, MeshNeeds::Frames); !p.empty())
        return p;
    if (a.mesh.uvs1.size() != a.mesh.vertex_count())
        return "the mesh has no lightmap UVs (mesh.uvs1)";
    if (std::string p = surface_problem(a.mesh, a.materials, a.images, a.primitives); !p.empty())
        return p;
    if (a.width == 0 || a.height == 0 || a.width > kMaxAtlasSide || a.height > kMaxAtlasSide)
        return "atlas size " + std::to_string(a.width) + "x" + std::to_string(a.height) + " is not in [1, " +
               std::to_string(kMaxAtlasSide) + "]";
    if (outputs && a.outputs.empty())
        return "no outputs";
    if (std::string p = light_probes_problem(a.probes); !p.empty())
        return p;
    if (std::string p = lights_problem(a, !outputs); !p.empty())
        return p;
    if (a.reflections.size() > kMaxReflectionProbes)
        return std::to_string(a.reflections.size()) + " reflection probes, more than " +
               std::to_string(kMaxReflectionProbes);
    for (size_t i = 0; i < a.reflections.size(); ++i)
    {
        const ReflectionProbe& r = a.reflections[i];
        const std::string which = "reflection probe " + std::to_string(i);
        if (!finite3(r.centre) || !finite3(r.box_min) || !finite3(r.box_max) ||
            !(r.box_min.x < r.box_max.x && r.box_min.y < r.box_max.y && r.box_min.z < r.box_max.z))
            return which + ": its centre or box is not finite, or the box's minimum is not below its maximum";
        if (std::string p = envmap_problem(r.maps); !p.empty())
            return which + ": " + p;
    }
    if (outputs)
        for (const LightmapOutput& o : a.outputs)
            if (std::string p = output_problem(o, a.width, a.height); !p.empty())
                return p;
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

struct LightmapAssetWriter::Sections
{
    explicit Sections(const std::filesystem::path& spool) : writer(spool) {}
    Sections() = default;
    AssetWriter writer;
};

LightmapAssetWriter::LightmapAssetWriter(const LightmapAsset& a, const std::filesystem::path& spool)
    : asset_(&a), sections_(spool.empty() ? std::make_unique<Sections>() : std::make_unique<Sections>(spool))
{
    if (std::string p = problem(a, false); !p.empty())
        throw std::invalid_argument("hemi: cannot write a lightmap asset: " + p);
    mixed_ = std::any_of(a.lights.begin(), a.lights.end(),
                         [](const LightmapLight& l) { return l.light.mode == LightMode::Mixed; });
    const Info info{
        mixed_ ? kLightmapLayoutVersion : 3u, a.width, a.height, a.rays, a.seed, a.bounces, a.covered_texels};
    sections_->writer.add("lightmap.info", std::as_bytes(std::span<const Info>(&info, 1)));
    write_scene_sections(sections_->writer, a.mesh, a.materials, a.images, a.primitives);
}

LightmapAssetWriter::~LightmapAssetWriter() = default;

namespace
{
// An output's section: u32 K, u32 N, i32 e, N u32 block indices, then the values / 2^e as half floats,
// encoded piece by piece as the container asks for them (straight into its spool when it has one).
// An output's section: K, the block count, the scale's exponent and the block list, then every value as a
// half float (value / 2^exponent), in BlockMaps' order, taken from `values(first, out)` a piece at a time.
struct OutputSection
{
    using Values = std::function<void(uint64_t first, std::span<float> out)>;
    OutputSection(const std::string& name_, uint32_t k, const BlockGrid& grid, int32_t exponent_,
                  Values values_)
        : name(name_), count(uint64_t(grid.slots()) * k * 3), exponent(exponent_), values(std::move(values_))
    {
        const std::vector<uint32_t>& blocks = grid.blocks();
        head.resize(3 + blocks.size());
        head[0] = k;
        head[1] = uint32_t(blocks.size());
        std::memcpy(&head[2], &exponent, 4);
        if (!blocks
                 .empty()) // an output with no blocks: all 0 (memcpy from null is undefined even for 0 bytes)
            std::memcpy(head.data() + 3, blocks.data(), blocks.size() * 4);
    }
    // A whole output in memory (checked first).
    static OutputSection of(const LightmapOutput& o, uint32_t width, uint32_t height)
    {
        if (std::string p = output_problem(o, width, height); !p.empty())
            throw std::invalid_argument("hemi: cannot write a lightmap asset: " + p);
        return OutputSection(
            o.name, o.k, o.maps.grid, half_scale_exponent(largest_magnitude(o.maps.values)),
            [&o](uint64_t first, std::span<float> out)
            { std::copy_n(o.maps.values.begin() + ptrdiff_t(first), out.size(), out.begin()); });
    }
    uint64_t head_bytes() const { return head.size() * 4; }
    uint64_t size() const { return head_bytes() + count * 2; }
    void fill(uint64_t offset, std::span<std::byte> out)
    {
        size_t at = 0;
        if (offset < head_bytes())
        {
            at = size_t(std::min<uint64_t>(head_bytes() - offset, out.size()));
            std::memcpy(out.data(), reinterpret_cast<const std::byte*>(head.data()) + offset, at);
        }
        // The head and every piece have an even size: values start on a whole half float.
        const uint64_t first = (offset + at - head_bytes()) / 2;
        piece.resize((out.size() - at) / 2);
        if (piece.empty())
            return;
        values(first, piece);
        for (size_t v = 0; v < piece.size(); ++v, at += 2)
        {
            if (!std::isfinite(piece[v]))
                throw std::invalid_argument("hemi: cannot write a lightmap asset: output '" + name +
                                            "' holds a value that is not finite");
            const uint16_t h = glm::packHalf1x16(std::ldexp(piece[v], -exponent));
            std::memcpy(out.data() + at, &h, 2);
        }
    }
    std::string name;
    uint64_t count; // values
    int32_t exponent = 0;
    Values values;
    std::vector<uint32_t> head;
    std::vector<float> piece;
};
} // namespace

void LightmapAssetWriter::add_output(const LightmapOutput& o)
{
    OutputSection section = OutputSection::of(o, asset_->width, asset_->height);
    sections_->writer.add_generated("L." + o.name, section.size(),
                                    [&](uint64_t offset, std::span<std::byte> out)
                                    { section.fill(offset, out); });
    ++outputs_;
}

void LightmapAssetWriter::add_output(const std::string& name, uint32_t k, const BlockGrid& grid,
                                     int32_t exponent,
                                     const std::function<void(uint64_t first, std::span<float> out)>& values)
{
    // output_problem's checks but the values' (which come as they are written, checked then).
    if (expected_k(name) == 0 || expected_k(name) != k || grid.width() != asset_->width ||
        grid.height() != asset_->height)
        throw std::invalid_argument("hemi: cannot write a lightmap asset: output '" + name + "' with K = " +
                                    std::to_string(k) + " over a " + std::to_string(grid.width()) + "x" +
                                    std::to_string(grid.height()) + " grid does not fit");
    OutputSection section(name, k, grid, exponent, values);
    sections_->writer.add_generated("L." + name, section.size(),
                                    [&](uint64_t offset, std::span<std::byte> out)
                                    { section.fill(offset, out); });
    ++outputs_;
}

std::vector<std::byte> LightmapAssetWriter::encode_output(const LightmapOutput& o, uint32_t width,
                                                          uint32_t height)
{
    OutputSection section = OutputSection::of(o, width, height);
    std::vector<std::byte> bytes(size_t(section.size()));
    section.fill(0, bytes);
    return bytes;
}

void LightmapAssetWriter::add_encoded_output(const std::string& name, std::span<const std::byte> bytes)
{
    sections_->writer.add("L." + name, bytes);
    ++outputs_;
}

void LightmapAssetWriter::set_shadowmask(const BlockGrid& grid,
                                         std::function<void(uint64_t first, std::span<float> out)> values)
{
    if (!mixed_ || asset_->shadowmask.k != 0 || grid.width() != asset_->width ||
        grid.height() != asset_->height)
        throw std::invalid_argument("hemi: cannot write a lightmap asset: a shadowmask over a " +
                                    std::to_string(grid.width()) + "x" + std::to_string(grid.height()) +
                                    " grid for an asset " +
                                    (mixed_ ? "that has one or another size" : "without mixed lights"));
    shadowmask_grid_ = grid;
    shadowmask_values_ = std::move(values);
}

void LightmapAssetWriter::write(const std::filesystem::path& path)
{
    if (outputs_ == 0)
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": no outputs");
    if (!asset_->probes.empty())
    {
        const LightProbes& p = asset_->probes;
        const ProbeHeader header{p.count.x,
                                 p.count.y,
                                 p.count.z,
                                 p.scattered() ? 1u : 0u,
                                 {p.lo.x, p.lo.y, p.lo.z},
                                 {p.hi.x, p.hi.y, p.hi.z}};
        const size_t base = sizeof header + p.irradiance.size() * 27 * 4 + p.valid.size();
        std::vector<std::byte> bytes(base + p.occlusion.size() * 4);
        std::memcpy(bytes.data(), &header, sizeof header);
        std::memcpy(bytes.data() + sizeof header, p.irradiance.data(), p.irradiance.size() * 27 * 4);
        std::memcpy(bytes.data() + sizeof header + p.irradiance.size() * 27 * 4, p.valid.data(),
                    p.valid.size());
        for (size_t i = 0; i < p.occlusion.size(); ++i)
            for (size_t c = 0; c < 4; ++c)
                bytes[base + i * 4 + c] =
                    std::byte(uint8_t(std::lround(std::clamp(p.occlusion[i][c], 0.0f, 1.0f) * 255.0f)));
        sections_->writer.add("lightmap.probes", bytes);
        if (p.scattered())
            sections_->writer.add("lightmap.probe_points",
                                  std::as_bytes(std::span(p.points.data(), p.points.size())));
        if (!p.depth.empty())
        {
            const uint32_t r = p.depth_resolution;
            std::vector<std::byte> depth(8 + p.depth.size() * 4);
            std::memcpy(depth.data(), &r, 4);
            std::memcpy(depth.data() + 4, &p.max_distance, 4);
            for (size_t i = 0; i < p.depth.size(); ++i)
            {
                const uint16_t h[2] = {glm::packHalf1x16(p.depth[i].x / p.max_distance),
                                       glm::packHalf1x16(p.depth[i].y / p.max_distance)};
                std::memcpy(depth.data() + 8 + i * 4, h, 4);
            }
            sections_->writer.add("lightmap.probe_depth", depth);
        }
    }
    if (!asset_->reflections.empty())
    {
        const uint32_t count = uint32_t(asset_->reflections.size());
        std::vector<std::byte> bytes(4 + size_t(count) * 36);
        std::memcpy(bytes.data(), &count, 4);
        for (uint32_t i = 0; i < count; ++i)
        {
            const ReflectionProbe& r = asset_->reflections[i];
            const float v[9] = {r.centre.x,  r.centre.y,  r.centre.z,  r.box_min.x, r.box_min.y,
                                r.box_min.z, r.box_max.x, r.box_max.y, r.box_max.z};
            std::memcpy(bytes.data() + 4 + size_t(i) * 36, v, 36);
            add_envmap_sections(sections_->writer, r.maps, "reflection" + std::to_string(i));
        }
        sections_->writer.add("lightmap.reflections", bytes);
    }
    if (!asset_->lights.empty())
    {
        std::vector<std::byte> bytes(4);
        const uint32_t count = uint32_t(asset_->lights.size());
        std::memcpy(bytes.data(), &count, 4);
        for (const LightmapLight& l : asset_->lights)
        {
            const PunctualLight& p = l.light;
            const LightRecord r{uint32_t(p.type),
                                uint32_t(p.mode),
                                l.channel,
                                {p.color.r, p.color.g, p.color.b},
                                p.intensity,
                                p.range,
                                p.inner_cone,
                                p.outer_cone,
                                {p.position.x, p.position.y, p.position.z},
                                {p.direction.x, p.direction.y, p.direction.z},
                                l.angular_diameter_degrees,
                                uint32_t(p.name.size())};
            const size_t at = bytes.size();
            bytes.resize(at + sizeof r + p.name.size());
            std::memcpy(bytes.data() + at, &r, sizeof r);
            std::memcpy(bytes.data() + at + sizeof r, p.name.data(), p.name.size());
        }
        sections_->writer.add("lightmap.lights", bytes);
    }
    if (mixed_)
    {
        // u32 N, the blocks, then per texel of each block its 4 channels as u8, made a block at a time from
        // set_shadowmask's values or the asset's shadowmask.
        const bool pulled = bool(shadowmask_values_);
        if (!pulled && asset_->shadowmask.k != 4)
            throw std::invalid_argument("hemi: cannot write " + path.string() +
                                        ": mixed lights without a shadowmask of 4 channels");
        const BlockGrid& grid = pulled ? shadowmask_grid_ : asset_->shadowmask.grid;
        const std::vector<uint32_t>& blocks = grid.blocks();
        const uint64_t head = 4 + uint64_t(blocks.size()) * 4;
        constexpr size_t kBlockValues = 4 * BlockGrid::kTexels * 3;
        std::vector<float> block(kBlockValues);
        uint64_t block_at = UINT64_MAX; // the block `block` holds
        sections_->writer.add_generated(
            "lightmap.shadowmask", head + grid.slots() * 4,
            [&](uint64_t offset, std::span<std::byte> out)
            {
                for (size_t i = 0; i < out.size(); ++i)
                {
                    const uint64_t at = offset + i;
                    if (at < head)
                    {
                        const uint32_t word = at < 4 ? uint32_t(blocks.size()) : blocks[size_t(at / 4 - 1)];
                        out[i] = std::byte(uint8_t(word >> (8 * (at % 4))));
                        continue;
                    }
                    const uint64_t texel = (at - head) / 4, b = texel / BlockGrid::kTexels;
                    if (b != block_at)
                    {
                        if (pulled)
                            shadowmask_values_(b * kBlockValues, block);
                        else
                            std::copy_n(&asset_->shadowmask.values[size_t(b) * kBlockValues], kBlockValues,
                                        block.begin());
                        block_at = b;
                    }
                    const uint32_t c = uint32_t((at - head) % 4), t = uint32_t(texel % BlockGrid::kTexels);
                    const float v = block[(c * BlockGrid::kTexels + t) * 3];
                    if (!(v >= 0.0f && v <= 1.0f))
                        throw std::invalid_argument("hemi: cannot write " + path.string() +
                                                    ": the shadowmask holds a value outside [0, 1]");
                    out[i] = std::byte(uint8_t(std::lround(v * 255.0f)));
                }
            });
    }
    sections_->writer.write(path);
}

void write_lightmap_asset(const std::filesystem::path& path, const LightmapAsset& a)
{
    if (std::string p = problem(a); !p.empty())
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": " + p);
    LightmapAssetWriter writer(a);
    for (const LightmapOutput& o : a.outputs)
        writer.add_output(o);
    writer.write(path);
}

namespace
{
LightmapAsset read_lightmap_asset_from(const AssetReader& r)
{
    const std::string file = r.name();
    auto fail = [&](const std::string& what) -> FormatError { return FormatError(file + ": " + what); };
    if (!r.has("lightmap.info"))
        throw fail(r.has("prt.info") ? "a PRT asset, not a lightmap asset"
                                     : "not a lightmap asset (no lightmap.info)");
    const std::span<const std::byte> info_bytes = r.section("lightmap.info");
    if (info_bytes.size() != sizeof(Info))
        throw fail("lightmap.info has " + std::to_string(info_bytes.size()) + " bytes, expected " +
                   std::to_string(sizeof(Info)));
    Info info;
    std::memcpy(&info, info_bytes.data(), sizeof info);
    if (info.layout < 1 || info.layout > kLightmapLayoutVersion)
        throw fail("lightmap layout version " + std::to_string(info.layout) +
                   " is not supported (this hemi reads 1 to " + std::to_string(kLightmapLayoutVersion) + ")");
    if (info.width == 0 || info.height == 0 || info.width > kMaxAtlasSide || info.height > kMaxAtlasSide)
        throw fail("lightmap.info: atlas size " + std::to_string(info.width) + "x" +
                   std::to_string(info.height) + " is not in [1, " + std::to_string(kMaxAtlasSide) + "]");
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
        auto half = [&](size_t offset)
        {
            uint16_t h;
            std::memcpy(&h, b.data() + offset, 2);
            return glm::unpackHalf1x16(h);
        };
        if (info.layout == 1)
        {
            // The dense atlas: K x H x W x 3 halves after K.
            const uint64_t expected = 4 + uint64_t(k) * texels * 3 * 2;
            if (b.size() != expected)
                throw fail(section + " has " + std::to_string(b.size()) + " bytes, a " +
                           std::to_string(a.width) + "x" + std::to_string(a.height) +
                           " atlas of K = " + std::to_string(k) + " needs " + std::to_string(expected));
            std::vector<float> dense(size_t(k) * texels * 3);
            for (size_t i = 0; i < dense.size(); ++i)
                dense[i] = half(4 + 2 * i);
            o.maps = BlockMaps::from_dense(a.width, a.height, k, dense);
        }
        else
        {
            // K, N, (layout 3) e, N block indices, N x K x 64 x 3 halves.
            const uint64_t head = info.layout >= 3 ? 12 : 8;
            if (b.size() < head)
                throw fail(section + " is too short");
            uint32_t n = 0;
            std::memcpy(&n, b.data() + 4, 4);
            int32_t exponent = 0;
            if (info.layout >= 3)
                std::memcpy(&exponent, b.data() + 8, 4);
            if (exponent < kMinHalfScaleExponent || exponent > kMaxHalfScaleExponent)
                throw fail(section + ": scale 2^" + std::to_string(exponent) + " is outside 2^" +
                           std::to_string(kMinHalfScaleExponent) + " to 2^" +
                           std::to_string(kMaxHalfScaleExponent));
            const uint64_t grid = uint64_t((a.width + 7) / 8) * ((a.height + 7) / 8);
            const uint64_t expected = head + uint64_t(n) * 4 + uint64_t(n) * k * BlockGrid::kTexels * 3 * 2;
            if (n > grid)
                throw fail(section + " lists " + std::to_string(n) + " blocks, but a " +
                           std::to_string(a.width) + "x" + std::to_string(a.height) + " atlas has " +
                           std::to_string(grid));
            if (b.size() != expected)
                throw fail(section + " has " + std::to_string(b.size()) + " bytes, " + std::to_string(n) +
                           " blocks of K = " + std::to_string(k) + " need " + std::to_string(expected));
            std::vector<uint32_t> blocks(n);
            if (n > 0)
                std::memcpy(blocks.data(), b.data() + head, size_t(n) * 4);
            try
            {
                o.maps = BlockMaps(BlockGrid(a.width, a.height, std::move(blocks)), k);
            }
            catch (const std::invalid_argument& e)
            {
                throw fail(section + ": " + e.what());
            }
            const size_t base = size_t(head) + size_t(n) * 4;
            for (size_t i = 0; i < o.maps.values.size(); ++i)
                o.maps.values[i] = std::ldexp(half(base + 2 * i), exponent);
        }
        a.outputs.push_back(std::move(o));
    }
    if (r.has("lightmap.probes"))
    {
        const std::span<const std::byte> b = r.section("lightmap.probes");
        ProbeHeader header{};
        if (b.size() < sizeof header)
            throw fail("lightmap.probes is too short");
        std::memcpy(&header, b.data(), sizeof header);
        const uint64_t n = probe_grid_count(header.nx, header.ny, header.nz);
        if (header.zero > 1)
            throw fail("lightmap.probes: probes of kind " + std::to_string(header.zero) +
                       " are not supported (0: a grid, 1: scattered)");
        const bool scattered = header.zero == 1;
        if (scattered && (header.ny != 1 || header.nz != 1))
            throw fail("lightmap.probes: " + std::to_string(header.nx) + "x" + std::to_string(header.ny) +
                       "x" + std::to_string(header.nz) + " scattered probes, expected Nx1x1");
        if (scattered != r.has("lightmap.probe_points"))
            throw fail(scattered ? "lightmap.probes: scattered probes without lightmap.probe_points"
                                 : "lightmap.probe_points with a grid of probes");
        if (n == 0)
            throw fail("lightmap.probes: a grid of " + std::to_string(header.nx) + "x" +
                       std::to_string(header.ny) + "x" + std::to_string(header.nz) +
                       " probes is not supported");
        const uint64_t base = sizeof header + n * 27 * 4 + n;
        if (b.size() != base && b.size() != base + n * 4)
            throw fail("lightmap.probes has " + std::to_string(b.size()) + " bytes, " + std::to_string(n) +
                       " probes need " + std::to_string(base) + " (" + std::to_string(base + n * 4) +
                       " with the mixed lights' occlusion)");
        LightProbes& p = a.probes;
        p.count = glm::uvec3(header.nx, header.ny, header.nz);
        p.lo = glm::vec3(header.lo[0], header.lo[1], header.lo[2]);
        p.hi = glm::vec3(header.hi[0], header.hi[1], header.hi[2]);
        p.irradiance.resize(size_t(n));
        p.valid.resize(size_t(n));
        std::memcpy(p.irradiance.data(), b.data() + sizeof header, size_t(n) * 27 * 4);
        std::memcpy(p.valid.data(), b.data() + sizeof header + size_t(n) * 27 * 4, size_t(n));
        if (scattered)
        {
            const std::span<const std::byte> q = r.section("lightmap.probe_points");
            if (q.size() != n * 16)
                throw fail("lightmap.probe_points has " + std::to_string(q.size()) + " bytes, " +
                           std::to_string(n) + " probes need " + std::to_string(n * 16));
            p.points.resize(size_t(n));
            std::memcpy(p.points.data(), q.data(), q.size());
        }
        if (b.size() > base)
        {
            p.occlusion.resize(size_t(n));
            for (size_t i = 0; i < size_t(n); ++i)
                for (size_t c = 0; c < 4; ++c)
                    p.occlusion[i][c] = float(uint8_t(b[size_t(base) + i * 4 + c])) / 255.0f;
        }
        if (r.has("lightmap.probe_depth"))
        {
            const std::span<const std::byte> d = r.section("lightmap.probe_depth");
            uint32_t resolution = 0;
            if (d.size() < 8)
                throw fail("lightmap.probe_depth is too short");
            std::memcpy(&resolution, d.data(), 4);
            std::memcpy(&p.max_distance, d.data() + 4, 4);
            if (resolution == 0 || resolution > kMaxProbeDepthResolution)
                throw fail("lightmap.probe_depth: depth maps of " + std::to_string(resolution) +
                           " texels a side are not supported");
            const uint64_t depth_texels = n * resolution * resolution;
            if (d.size() != 8 + depth_texels * 4)
                throw fail("lightmap.probe_depth has " + std::to_string(d.size()) + " bytes, " +
                           std::to_string(n) + " probes of " + std::to_string(resolution) + "x" +
                           std::to_string(resolution) + " texels need " +
                           std::to_string(8 + depth_texels * 4));
            if (!(p.max_distance > 0.0f) || !std::isfinite(p.max_distance))
                throw fail("lightmap.probe_depth: the largest distance is not a positive finite number");
            p.depth_resolution = resolution;
            p.depth.resize(size_t(depth_texels));
            for (size_t i = 0; i < p.depth.size(); ++i)
            {
                uint16_t h[2];
                std::memcpy(h, d.data() + 8 + i * 4, 4);
                p.depth[i] = glm::vec2(glm::unpackHalf1x16(h[0]), glm::unpackHalf1x16(h[1])) * p.max_distance;
            }
        }
    }
    else if (r.has("lightmap.probe_depth") || r.has("lightmap.probe_points"))
        throw fail(
            std::string(r.has("lightmap.probe_depth") ? "lightmap.probe_depth" : "lightmap.probe_points") +
            " without lightmap.probes");
    if (r.has("lightmap.reflections"))
    {
        const std::span<const std::byte> b = r.section("lightmap.reflections");
        uint32_t count = 0;
        if (b.size() < 4)
            throw fail("lightmap.reflections is too short");
        std::memcpy(&count, b.data(), 4);
        if (count > kMaxReflectionProbes || b.size() != 4 + size_t(count) * 36)
            throw fail("lightmap.reflections has " + std::to_string(b.size()) + " bytes for " +
                       std::to_string(count) + " probes (at most " + std::to_string(kMaxReflectionProbes) +
                       ", 36 bytes each)");
        for (uint32_t i = 0; i < count; ++i)
        {
            float v[9];
            std::memcpy(v, b.data() + 4 + size_t(i) * 36, 36);
            ReflectionProbe probe;
            probe.centre = glm::vec3(v[0], v[1], v[2]);
            probe.box_min = glm::vec3(v[3], v[4], v[5]);
            probe.box_max = glm::vec3(v[6], v[7], v[8]);
            probe.maps = read_envmap_sections(r, "reflection" + std::to_string(i));
            a.reflections.push_back(std::move(probe));
        }
    }
    if (r.has("lightmap.lights"))
    {
        const std::span<const std::byte> b = r.section("lightmap.lights");
        uint32_t count = 0;
        if (b.size() < 4)
            throw fail("lightmap.lights is too short");
        std::memcpy(&count, b.data(), 4);
        size_t at = 4;
        for (uint32_t i = 0; i < count; ++i)
        {
            LightRecord rec;
            if (b.size() - at < sizeof rec)
                throw fail("lightmap.lights ends inside light " + std::to_string(i) + " of " +
                           std::to_string(count));
            std::memcpy(&rec, b.data() + at, sizeof rec);
            at += sizeof rec;
            if (rec.type > 2 || rec.mode > 2)
                throw fail("lightmap.lights: light " + std::to_string(i) + " has type " +
                           std::to_string(rec.type) + " and bake mode " + std::to_string(rec.mode));
            if (b.size() - at < rec.name_length)
                throw fail("lightmap.lights ends inside the name of light " + std::to_string(i));
            LightmapLight l;
            PunctualLight& p = l.light;
            p.type = PunctualLight::Type(rec.type);
            p.mode = LightMode(rec.mode);
            p.name.assign(reinterpret_cast<const char*>(b.data() + at), rec.name_length);
            at += rec.name_length;
            p.color = glm::vec3(rec.color[0], rec.color[1], rec.color[2]);
            p.intensity = rec.intensity;
            p.range = rec.range;
            p.inner_cone = rec.inner_cone;
            p.outer_cone = rec.outer_cone;
            p.position = glm::vec3(rec.position[0], rec.position[1], rec.position[2]);
            p.direction = glm::vec3(rec.direction[0], rec.direction[1], rec.direction[2]);
            l.angular_diameter_degrees = rec.angular_diameter;
            l.channel = rec.channel;
            a.lights.push_back(std::move(l));
        }
        if (at != b.size())
            throw fail("lightmap.lights has " + std::to_string(b.size() - at) + " bytes after its " +
                       std::to_string(count) + " lights");
    }
    if (r.has("lightmap.shadowmask"))
    {
        const std::span<const std::byte> b = r.section("lightmap.shadowmask");
        uint32_t n = 0;
        if (b.size() < 4)
            throw fail("lightmap.shadowmask is too short");
        std::memcpy(&n, b.data(), 4);
        const uint64_t grid = uint64_t((a.width + 7) / 8) * ((a.height + 7) / 8);
        if (n > grid)
            throw fail("lightmap.shadowmask lists " + std::to_string(n) + " blocks, but a " +
                       std::to_string(a.width) + "x" + std::to_string(a.height) + " atlas has " +
                       std::to_string(grid));
        const uint64_t expected = 4 + uint64_t(n) * 4 + uint64_t(n) * BlockGrid::kTexels * 4;
        if (b.size() != expected)
            throw fail("lightmap.shadowmask has " + std::to_string(b.size()) + " bytes, " +
                       std::to_string(n) + " blocks need " + std::to_string(expected));
        std::vector<uint32_t> blocks(n);
        if (n > 0)
            std::memcpy(blocks.data(), b.data() + 4, size_t(n) * 4);
        try
        {
            a.shadowmask = BlockMaps(BlockGrid(a.width, a.height, std::move(blocks)), 4);
        }
        catch (const std::invalid_argument& e)
        {
            throw fail("lightmap.shadowmask: " + std::string(e.what()));
        }
        const std::byte* mask = b.data() + 4 + size_t(n) * 4;
        BlockMaps& m = a.shadowmask;
        for (size_t slot = 0; slot < m.grid.slots(); ++slot)
            for (uint32_t c = 0; c < 4; ++c)
            {
                const float v = float(uint8_t(mask[slot * 4 + c])) / 255.0f;
                float* rgb = &m.values[m.index(c, slot)];
                rgb[0] = rgb[1] = rgb[2] = v;
            }
    }
    if (std::string p = problem(a); !p.empty())
        throw fail(p);
    return a;
}
} // namespace

LightmapAsset read_lightmap_asset(const std::filesystem::path& path)
{
    return read_lightmap_asset_from(AssetReader(path));
}

LightmapAsset read_lightmap_asset(std::span<const std::byte> bytes, const std::string& name)
{
    return read_lightmap_asset_from(AssetReader(bytes, name));
}

std::string asset_kind(const std::filesystem::path& path)
{
    const AssetReader r(path);
    if (r.has("lightmap.info"))
        return "lightmap";
    if (r.has("prt.info"))
        return "prt";
    if (r.has("envmap.info"))
        return "envmap";
    throw FormatError(path.string() + ": a hemi container, but not a PRT, lightmap or environment asset");
}

} // namespace hemi::io
