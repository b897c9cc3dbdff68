#include <hemi/io/asset.h>
#include <hemi/io/envmap_asset.h>
#include <hemi/io/image.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::io
{
namespace
{
constexpr uint32_t kEnvmapLayoutVersion = 1;

struct Info
{
    uint32_t layout, size, levels, glossy, fresnel_tables, fresnel_samples, source_width, source_height;
    float extent;
};

size_t image_floats(uint32_t size)
{
    return size_t(2) * size * size * 3;
}

} // namespace

std::string envmap_problem(const EnvmapAsset& a)
{
    if (a.mirror.empty())
        return "no mirror map";
    for (size_t l = 0; l < a.mirror.size(); ++l)
        if (a.mirror[l].size != (a.mirror[0].size >> l) ||
            a.mirror[l].rgb.size() != image_floats(a.mirror[l].size))
            return "mirror level " + std::to_string(l) + " has the wrong size";
    if (a.mirror.back().size != 1)
        return "the mirror map's mip chain does not end at 1x1";
    if (a.exponents.size() != a.glossy.size())
        return "one exponent per glossy map";
    for (const math::ParabolicImage& g : a.glossy)
        if (g.size == 0 || g.rgb.size() != image_floats(g.size))
            return "a glossy map's size does not match its texels";
    if (a.diffuse.size == 0 || a.diffuse.rgb.size() != image_floats(a.diffuse.size))
        return "the diffuse map's size does not match its texels";
    if (a.fresnel.size() != a.iors.size() * a.fresnel_samples || (!a.iors.empty() && a.fresnel_samples < 2))
        return "the Fresnel tables' sizes disagree";
    if (a.glossy.size() > 64 || a.iors.size() > 64 || a.fresnel_samples > 65536)
        return "at most 64 glossy maps, 64 Fresnel tables of 65536 samples";
    if ((a.mirror[0].size & (a.mirror[0].size - 1)) != 0)
        return "the mirror map's size is not a power of two";
    for (float e : a.exponents)
        if (!std::isfinite(e) || !(e > 0.0f))
            return "a glossy map's exponent is not > 0";
    for (float n : a.iors)
        if (!std::isfinite(n) || !(n > 1.0f))
            return "an index of refraction is not > 1";
    return {};
}

namespace
{

// Reads sequentially from a section; every read is checked against its end.
class Cursor
{
  public:
    Cursor(std::span<const std::byte> bytes, std::string what, const std::string& file)
        : bytes_(bytes), what_(std::move(what)), file_(file)
    {
    }
    template <typename T> T value()
    {
        T v;
        read(&v, sizeof v);
        return v;
    }
    std::vector<float> floats(size_t n)
    {
        if (n > (bytes_.size() - at_) / 4)
            throw FormatError(file_ + ": " + what_ + " is too short (truncated or inconsistent sizes)");
        std::vector<float> v(n);
        read(v.data(), n * 4);
        for (float f : v)
            if (!std::isfinite(f))
                throw FormatError(file_ + ": " + what_ + " holds a value that is not finite");
        return v;
    }
    void end() const
    {
        if (at_ != bytes_.size())
            throw FormatError(file_ + ": " + what_ + " has " + std::to_string(bytes_.size() - at_) +
                              " bytes too many");
    }

  private:
    void read(void* out, size_t n)
    {
        if (n > bytes_.size() - at_)
            throw FormatError(file_ + ": " + what_ + " is too short (truncated or inconsistent sizes)");
        std::memcpy(out, bytes_.data() + at_, n);
        at_ += n;
    }
    std::span<const std::byte> bytes_;
    size_t at_ = 0;
    std::string what_;
    const std::string& file_;
};

template <typename T> void append(std::vector<std::byte>& out, const T* data, size_t count)
{
    const auto* b = reinterpret_cast<const std::byte*>(data);
    out.insert(out.end(), b, b + count * sizeof(T));
}
} // namespace

void write_envmap_asset(const std::filesystem::path& path, const EnvmapAsset& a)
{
    if (std::string p = envmap_problem(a); !p.empty())
        throw std::invalid_argument("hemi: cannot write " + path.string() + ": " + p);
    AssetWriter w;
    add_envmap_sections(w, a, "envmap");
    w.write(path);
}

void add_envmap_sections(AssetWriter& w, const EnvmapAsset& a, const std::string& prefix)
{
    const Info info{kEnvmapLayoutVersion,
                    a.mirror[0].size,
                    uint32_t(a.mirror.size()),
                    uint32_t(a.glossy.size()),
                    uint32_t(a.iors.size()),
                    a.fresnel_samples,
                    a.source_width,
                    a.source_height,
                    float(a.mirror[0].extent)};
    w.add(prefix + ".info", std::as_bytes(std::span<const Info>(&info, 1)));
    std::vector<std::byte> mirror;
    for (const math::ParabolicImage& level : a.mirror)
        append(mirror, level.rgb.data(), level.rgb.size());
    w.add(prefix + ".mirror", mirror);
    std::vector<std::byte> glossy;
    for (size_t i = 0; i < a.glossy.size(); ++i)
    {
        append(glossy, &a.exponents[i], 1);
        append(glossy, &a.glossy[i].size, 1);
        const float extent = float(a.glossy[i].extent);
        append(glossy, &extent, 1);
        append(glossy, a.glossy[i].rgb.data(), a.glossy[i].rgb.size());
    }
    w.add(prefix + ".glossy", glossy);
    std::vector<std::byte> diffuse;
    append(diffuse, &a.diffuse.size, 1);
    const float diffuse_extent = float(a.diffuse.extent);
    append(diffuse, &diffuse_extent, 1);
    append(diffuse, a.diffuse.rgb.data(), a.diffuse.rgb.size());
    w.add(prefix + ".diffuse", diffuse);
    std::vector<std::byte> fresnel;
    for (size_t i = 0; i < a.iors.size(); ++i)
    {
        append(fresnel, &a.iors[i], 1);
        append(fresnel, a.fresnel.data() + i * a.fresnel_samples, a.fresnel_samples);
    }
    w.add(prefix + ".fresnel", fresnel);
}

EnvmapAsset read_envmap_sections(const AssetReader& r, const std::string& prefix)
{
    const std::string file = r.name();
    auto fail = [&](const std::string& what) { return FormatError(file + ": " + what); };
    const std::string info_name = prefix + ".info", mirror_name = prefix + ".mirror",
                      glossy_name = prefix + ".glossy", diffuse_name = prefix + ".diffuse",
                      fresnel_name = prefix + ".fresnel";
    Cursor ci(r.section(info_name), info_name, file);
    const Info info = ci.value<Info>();
    ci.end();
    if (info.layout != kEnvmapLayoutVersion)
        throw fail("envmap layout version " + std::to_string(info.layout) +
                   " is not supported (this hemi reads " + std::to_string(kEnvmapLayoutVersion) + ")");
    auto check_size = [&](uint32_t size, const std::string& what)
    {
        if (size == 0 || size > 8192 || (size & (size - 1)) != 0)
            throw fail(what + ": size " + std::to_string(size) + " is not a power of two in [1, 8192]");
    };
    check_size(info.size, info_name);
    uint32_t levels = 1;
    while ((info.size >> (levels - 1)) > 1)
        ++levels;
    if (info.levels != levels)
        throw fail(info_name + ": " + std::to_string(info.levels) + " mirror levels for size " +
                   std::to_string(info.size) + ", expected " + std::to_string(levels));
    auto check_extent = [&](float extent, const std::string& what)
    {
        if (!std::isfinite(extent) || extent < 1.0f || extent > 4.0f)
            throw fail(what + ": extent " + std::to_string(extent) + " is not in [1, 4]");
    };
    check_extent(info.extent, info_name);
    if (info.glossy > 64 || info.fresnel_tables > 64 || info.fresnel_samples > 65536 ||
        (info.fresnel_tables > 0 && info.fresnel_samples < 2))
        throw fail(info_name + ": implausible counts (corrupt)");

    EnvmapAsset a;
    a.source_width = info.source_width;
    a.source_height = info.source_height;
    Cursor cm(r.section(mirror_name), mirror_name, file);
    for (uint32_t l = 0; l < info.levels; ++l)
    {
        math::ParabolicImage level;
        level.size = info.size >> l;
        level.extent = info.extent;
        level.rgb = cm.floats(image_floats(level.size));
        a.mirror.push_back(std::move(level));
    }
    cm.end();
    Cursor cg(r.section(glossy_name), glossy_name, file);
    for (uint32_t i = 0; i < info.glossy; ++i)
    {
        const float e = cg.value<float>();
        if (!std::isfinite(e) || !(e > 0.0f))
            throw fail(glossy_name + ": exponent " + std::to_string(e) + " is not > 0");
        math::ParabolicImage g;
        g.size = cg.value<uint32_t>();
        check_size(g.size, glossy_name);
        g.extent = cg.value<float>();
        check_extent(float(g.extent), glossy_name);
        g.rgb = cg.floats(image_floats(g.size));
        a.exponents.push_back(e);
        a.glossy.push_back(std::move(g));
    }
    cg.end();
    Cursor cd(r.section(diffuse_name), diffuse_name, file);
    a.diffuse.size = cd.value<uint32_t>();
    check_size(a.diffuse.size, diffuse_name);
    a.diffuse.extent = cd.value<float>();
    check_extent(float(a.diffuse.extent), diffuse_name);
    a.diffuse.rgb = cd.floats(image_floats(a.diffuse.size));
    cd.end();
    Cursor cf(r.section(fresnel_name), fresnel_name, file);
    a.fresnel_samples = info.fresnel_samples;
    for (uint32_t i = 0; i < info.fresnel_tables; ++i)
    {
        const float ior = cf.value<float>();
        if (!std::isfinite(ior) || !(ior > 1.0f))
            throw fail(fresnel_name + ": index of refraction " + std::to_string(ior) + " is not > 1");
        a.iors.push_back(ior);
        const std::vector<float> t = cf.floats(info.fresnel_samples);
        a.fresnel.insert(a.fresnel.end(), t.begin(), t.end());
    }
    cf.end();
    return a;
}

namespace
{
EnvmapAsset read_envmap_asset_from(const AssetReader& r)
{
    if (!r.has("envmap.info"))
        throw FormatError(r.name() + ": not an environment asset (no envmap.info)");
    return read_envmap_sections(r, "envmap");
}
} // namespace

EnvmapAsset read_envmap_asset(const std::filesystem::path& path)
{
    return read_envmap_asset_from(AssetReader(path));
}

EnvmapAsset read_envmap_asset(std::span<const std::byte> bytes, const std::string& name)
{
    return read_envmap_asset_from(AssetReader(bytes, name));
}

} // namespace hemi::io
