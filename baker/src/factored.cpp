#include <hemi/bake/factored.h>
#include <hemi/math/paraboloid.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <system_error>

namespace hemi::bake
{
namespace
{
constexpr double kPi = 3.14159265358979323846;

void check_finite_positive(double v, const char* what)
{
    if (!std::isfinite(v) || !(v > 0.0))
        throw std::invalid_argument(std::string(what) + " must be a finite number > 0, got " +
                                    std::to_string(v));
}

std::string number(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

// The dense set of direction pairs over which errors are measured, n = +z, t = +x: every (l, v) of a grid
// over the hemisphere (cosines at midpoints of 32 intervals, 32 azimuths each), i.e. 1024 x 1024 pairs.
std::vector<glm::dvec3> hemisphere_grid()
{
    std::vector<glm::dvec3> out;
    constexpr int kCos = 32, kPhi = 32;
    for (int i = 0; i < kCos; ++i)
    {
        const double c = (i + 0.5) / kCos, s = std::sqrt(1.0 - c * c);
        for (int j = 0; j < kPhi; ++j)
        {
            const double phi = 2.0 * kPi * (j + 0.25) / kPhi;
            out.emplace_back(s * std::cos(phi), s * std::sin(phi), c);
        }
    }
    return out;
}

template <typename Direct, typename Table> BrdfError measure(Direct direct, Table table)
{
    const std::vector<glm::dvec3> grid = hemisphere_grid();
    struct Sample
    {
        double direct, table;
        bool grazing;
    };
    std::vector<Sample> samples;
    samples.reserve(grid.size() * grid.size());
    double peak = 0.0;
    for (const glm::dvec3& l : grid)
        for (const glm::dvec3& v : grid)
        {
            const double d = direct(l, v), t = table(l, v);
            samples.push_back({d, t, l.z < 0.1 || v.z < 0.1});
            peak = std::max(peak, d);
        }
    BrdfError e;
    const double floor = 0.01 * peak;
    double bulk_sq = 0.0, grazing_sq = 0.0;
    for (const Sample& s : samples)
    {
        const double rel = std::abs(s.table - s.direct) / std::max(s.direct, floor);
        if (s.grazing)
        {
            e.grazing_max = std::max(e.grazing_max, rel);
            grazing_sq += rel * rel;
            ++e.grazing_samples;
        }
        else
        {
            e.bulk_max = std::max(e.bulk_max, rel);
            bulk_sq += rel * rel;
            ++e.bulk_samples;
        }
    }
    e.bulk_rms = e.bulk_samples ? std::sqrt(bulk_sq / e.bulk_samples) : 0.0;
    e.grazing_rms = e.grazing_samples ? std::sqrt(grazing_sq / e.grazing_samples) : 0.0;
    return e;
}

// Each table's product with its scales, against the model, over the dense set.
BrdfError measure_tables(const BrdfBakeOptions& o, const std::vector<math::BrdfTable>& tables,
                         const std::vector<std::vector<double>>& scales)
{
    const glm::dvec3 n(0, 0, 1), t(1, 0, 0);
    auto at = [&](size_t table, uint32_t channel, double u, double v)
    { return tables[table].lookup(channel, u, v) * scales[table][channel]; };
    if (o.model == "torrance-sparrow")
    {
        const math::TorranceSparrow m(math::parse_facet_distribution(o.distribution), o.roughness, o.ior);
        return measure([&](const glm::dvec3& l, const glm::dvec3& v) { return m.eval_cos(n, l, v); },
                       [&](const glm::dvec3& l, const glm::dvec3& v)
                       {
                           const glm::dvec3 h = glm::normalize(l + v);
                           return at(0, 0, glm::dot(l, h), glm::dot(n, h)) * at(1, 0, l.z, v.z);
                       });
    }
    if (o.model == "banks")
        return measure([&](const glm::dvec3& l, const glm::dvec3& v)
                       { return math::banks_eval_cos(n, t, l, v, 1.0, 1.0, o.exponent); },
                       [&](const glm::dvec3& l, const glm::dvec3& v) {
                           return l.z * (at(0, 0, glm::dot(t, l), glm::dot(t, v)) +
                                         at(0, 1, glm::dot(t, l), glm::dot(t, v)));
                       });
    const math::LobeModel model = math::parse_lobe_model(o.model);
    return measure([&](const glm::dvec3& l, const glm::dvec3& v)
                   { return math::lobe_eval_cos(model, o.exponent, n, l, v); },
                   [&](const glm::dvec3& l, const glm::dvec3& v)
                   {
                       double y;
                       if (model == math::LobeModel::BlinnPhong)
                           y = glm::dot(n, glm::normalize(l + v));
                       else
                           y = glm::dot(2.0 * v.z * n - v, l);
                       return at(0, 0, l.z, y);
                   });
}
} // namespace

BrdfBake bake_brdf(const BrdfBakeOptions& o)
{
    if (o.size < 2 || o.size > 8192)
        throw std::invalid_argument("--size must be in [2, 8192], got " + std::to_string(o.size));
    BrdfBake b;
    if (o.model == "torrance-sparrow")
    {
        check_finite_positive(o.roughness, "--roughness");
        if (!std::isfinite(o.ior) || !(o.ior > 1.0))
            throw std::invalid_argument("--ior, the index of refraction, must be a finite number > 1, got " +
                                        std::to_string(o.ior));
        const math::TorranceSparrow m(math::parse_facet_distribution(o.distribution), o.roughness, o.ior);
        b.tables = math::torrance_sparrow_tables(m, o.size);
    }
    else if (o.model == "banks")
    {
        check_finite_positive(o.exponent, "--exponent");
        b.tables = {math::banks_table(o.exponent, o.size)};
    }
    else
    {
        check_finite_positive(o.exponent, "--exponent");
        b.tables = {math::lobe_table(math::parse_lobe_model(o.model), o.exponent, o.size)};
    }
    for (const math::BrdfTable& t : b.tables)
        b.scales.emplace_back(t.channels, 1.0);
    b.float_error = measure_tables(o, b.tables, b.scales);
    b.error = b.float_error;
    if (o.eight_bit)
    {
        for (size_t k = 0; k < b.tables.size(); ++k)
        {
            math::BrdfTable& t = b.tables[k];
            for (uint32_t c = 0; c < t.channels; ++c)
            {
                double peak = 0.0;
                for (size_t i = c; i < t.values.size(); i += t.channels)
                    peak = std::max(peak, double(t.values[i]));
                const double scale = peak > 0.0 ? peak : 1.0;
                for (size_t i = c; i < t.values.size(); i += t.channels)
                    t.values[i] =
                        float(std::round(std::clamp(t.values[i] / scale, 0.0, 1.0) * 255.0) / 255.0);
                b.scales[k][c] = scale;
            }
        }
        b.error = measure_tables(o, b.tables, b.scales);
    }
    return b;
}

void write_brdf_exr(const std::filesystem::path& path, const BrdfBakeOptions& o, const BrdfBake& b)
{
    const uint32_t size = b.tables.at(0).size;
    std::vector<io::ExrChannel> channels;
    std::vector<std::pair<std::string, std::string>> attrs{
        {"hemi.kind", "brdf"},
        {"hemi.model", o.model},
        {"hemi.size", std::to_string(size)},
        {"hemi.encoding",
         o.eight_bit ? "unorm8 (value = stored * hemi.<channel>.scale; stored = k / 255)" : "float"},
        {"hemi.sampling",
         "sample i of an axis at coordinate i / (size - 1); a shader samples coordinate c at "
         "(c * (size - 1) + 0.5) / size; row 0 of the image is axis v = its first coordinate"},
        {"hemi.convention",
         "f_r cos(alpha) of the model (hemi's math/brdf.h); directions point away from the surface"},
    };
    if (o.model == "torrance-sparrow")
    {
        attrs.emplace_back("hemi.distribution", o.distribution);
        attrs.emplace_back("hemi.roughness", number(o.roughness));
        attrs.emplace_back("hemi.ior", number(o.ior));
        attrs.emplace_back("hemi.product",
                           "f_r cos(alpha) = FD(cos_theta, cos_delta) * G(cos_alpha, cos_beta)");
    }
    else
    {
        attrs.emplace_back("hemi.exponent", number(o.exponent));
        attrs.emplace_back("hemi.product", o.model == "banks"
                                               ? "f_r cos(alpha) = cos_alpha * (kd * diffuse + ks * specular)"
                                               : "f_r cos(alpha) = ks * specular (+ kd * n.l / pi)");
    }
    for (size_t k = 0; k < b.tables.size(); ++k)
    {
        const math::BrdfTable& t = b.tables[k];
        auto axis = [](const std::string& name) { return name + " from 0 to 1"; };
        for (uint32_t c = 0; c < t.channels; ++c)
        {
            channels.push_back({t.channel_names[c], t.values.data() + c, t.channels, false});
            const std::string key = "hemi." + t.channel_names[c];
            attrs.emplace_back(key + ".axis_u", axis(t.axis_u));
            attrs.emplace_back(key + ".axis_v", axis(t.axis_v));
            attrs.emplace_back(key + ".scale", number(b.scales[k][c]));
        }
    }
    attrs.emplace_back("hemi.error.bulk_max", number(b.error.bulk_max));
    attrs.emplace_back("hemi.error.grazing_max", number(b.error.grazing_max));
    io::write_exr_channels(path, size, size, channels, attrs);
}

void check_envmap_options(const EnvmapBakeOptions& o)
{
    if (o.size < 8 || o.size > 4096 || (o.size & (o.size - 1)) != 0)
        throw std::invalid_argument("--size must be a power of two in [8, 4096], got " +
                                    std::to_string(o.size));
    for (double e : o.exponents)
    {
        check_finite_positive(e, "every --exponents value");
        // The asset stores exponents as floats: one too small for a float would become 0 there, after the
        // work. Below 1e-6 a lobe is uniform to within float precision anyway.
        if (e < 1e-6)
            throw std::invalid_argument("every --exponents value must be at least 1e-6, got " +
                                        std::to_string(e));
        if (e > math::kMaxPhongExponent)
            throw std::invalid_argument("every --exponents value must be at most 1e6 (a mirror), got " +
                                        std::to_string(e));
    }
    if (o.exponents.size() > 64 || o.iors.size() > 64)
        throw std::invalid_argument("at most 64 --exponents and 64 --ior values");
    for (double n : o.iors)
        if (!std::isfinite(n) || !(n > 1.0))
            throw std::invalid_argument(
                "every --ior value (an index of refraction) must be a finite number > 1, got " +
                std::to_string(n));
    if (o.fresnel_samples < 2 || o.fresnel_samples > 65536)
        throw std::invalid_argument("the Fresnel table needs 2 to 65536 samples");
}

io::EnvmapAsset bake_envmap(const io::ImageRgba& env, const EnvmapBakeOptions& o, EnvmapBakeStats* stats,
                            const std::function<void(const std::string&)>& progress)
{
    check_envmap_options(o);
    if (env.width == 0 || env.height == 0 || env.pixels.size() != size_t(env.width) * env.height * 4)
        throw std::invalid_argument("the environment image is empty or inconsistent");
    if (env.width != 2 * env.height)
        throw std::invalid_argument(
            "the environment must be an equirectangular (latitude-longitude) image, 2:1; got " +
            std::to_string(env.width) + "x" + std::to_string(env.height));
    EnvmapBakeStats local;
    EnvmapBakeStats& s = stats ? *stats : local;
    auto say = [&](const std::string& what)
    {
        if (progress)
            progress(what);
    };
    using clock = std::chrono::steady_clock;
    auto seconds = [](clock::time_point t0)
    { return std::chrono::duration<double>(clock::now() - t0).count(); };

    io::EnvmapAsset a;
    a.source_width = env.width;
    a.source_height = env.height;
    say("resampling " + std::to_string(env.width) + "x" + std::to_string(env.height) + " into 2 x " +
        std::to_string(o.size) + "^2 parabolic texels");
    auto t0 = clock::now();
    math::ParabolicImage level0 = math::parabolic_from_equirect(o.size, env.width, env.height, env.pixels);
    s.resample_seconds = seconds(t0);
    say("solid-angle mipmaps");
    t0 = clock::now();
    a.mirror = math::parabolic_mip_chain(std::move(level0));
    s.mip_seconds = seconds(t0);
    say("diffuse map");
    t0 = clock::now();
    auto prefilter = [&](double e, math::PrefilterStats* counts)
    {
        return o.exact ? math::prefilter_phong_exact(a.mirror, e, counts)
                       : math::prefilter_phong(a.mirror, e, counts);
    };
    a.diffuse = prefilter(1.0, nullptr);
    s.diffuse_seconds = seconds(t0);
    for (double e : o.exponents)
    {
        say("glossy map, exponent " + number(e) + " (" + std::to_string(math::glossy_size(e, o.size)) +
            "^2)");
        math::PrefilterStats ps;
        a.glossy.push_back(prefilter(e, &ps));
        a.exponents.push_back(float(e));
        s.glossy_seconds.push_back(ps.seconds);
        s.glossy_pairs.push_back(ps.texel_pairs);
    }
    a.fresnel_samples = o.fresnel_samples;
    for (double n : o.iors)
    {
        a.iors.push_back(float(n));
        const std::vector<float> t = math::fresnel_table(n, o.fresnel_samples);
        a.fresnel.insert(a.fresnel.end(), t.begin(), t.end());
    }
    return a;
}

io::ImageRgba parabolic_half_image(const math::ParabolicImage& map, int half)
{
    io::ImageRgba out;
    out.width = out.height = map.size;
    out.pixels.resize(size_t(map.size) * map.size * 4);
    for (uint32_t row = 0; row < map.size; ++row)
        for (uint32_t col = 0; col < map.size; ++col)
        {
            const float* t = map.at(half, col, row);
            float* p = out.pixels.data() + (size_t(row) * map.size + col) * 4;
            p[0] = t[0], p[1] = t[1], p[2] = t[2];
            const double x = map.extent * (-1.0 + (col + 0.5) * 2.0 / map.size);
            const double y = map.extent * (1.0 - (row + 0.5) * 2.0 / map.size);
            p[3] = x * x + y * y <= 1.0 ? 1.0f : 0.0f;
        }
    return out;
}

std::vector<std::filesystem::path> write_envmap_exrs(const std::filesystem::path& dir,
                                                     const io::EnvmapAsset& a)
{
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec)
        throw io::FormatError(dir.string() + ": cannot create the directory: " + ec.message());
    std::vector<std::filesystem::path> written;
    auto write = [&](const math::ParabolicImage& img, const std::string& stem)
    {
        for (int half = 0; half < 2; ++half)
        {
            const std::filesystem::path p = dir / (stem + (half == 0 ? "_front.exr" : "_back.exr"));
            io::write_exr(p, parabolic_half_image(img, half));
            written.push_back(p);
        }
    };
    for (size_t l = 0; l < a.mirror.size(); ++l)
        write(a.mirror[l], "mirror_L" + std::to_string(l));
    for (size_t i = 0; i < a.glossy.size(); ++i)
        write(a.glossy[i], "glossy_e" + number(a.exponents[i]));
    write(a.diffuse, "diffuse");
    if (!a.iors.empty())
    {
        std::vector<std::string> names;
        std::vector<io::ExrChannel> channels;
        for (size_t i = 0; i < a.iors.size(); ++i)
            names.push_back("ior" + number(a.iors[i]));
        for (size_t i = 0; i < a.iors.size(); ++i)
            channels.push_back({names[i], a.fresnel.data() + i * a.fresnel_samples, 1, false});
        const std::filesystem::path p = dir / "fresnel.exr";
        const std::vector<std::pair<std::string, std::string>> attrs{
            {"hemi.sampling", "sample i at cos(theta) = i / (samples - 1)"}};
        io::write_exr_channels(p, a.fresnel_samples, 1, channels, attrs);
        written.push_back(p);
    }
    return written;
}

} // namespace hemi::bake
