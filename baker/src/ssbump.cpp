// Self-shadowed bump maps (Green 2007): height input, filter, normals, the exact height-field tracer and the
// bake. The definitions are in ssbump.h and docs/ssbump.md.
#include <hemi/bake/checkpoint.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/bake/ssbump.h>
#include <hemi/io/image.h>
#include <hemi/io/mesh.h>
#include <hemi/math/rnm_basis.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

std::string_view to_string(SsbumpConvention convention)
{
    return convention == SsbumpConvention::Valve ? "valve" : "normalized";
}

SsbumpConvention parse_ssbump_convention(std::string_view name)
{
    if (name == "normalized")
        return SsbumpConvention::Normalized;
    if (name == "valve")
        return SsbumpConvention::Valve;
    throw std::invalid_argument("unknown SSBump convention '" + std::string(name) +
                                "' (known: normalized, valve)");
}

glm::vec3 ssbump_weights(const glm::vec3& n, SsbumpConvention convention)
{
    const auto& b = math::rnm_basis();
    glm::vec3 d;
    for (int i = 0; i < 3; ++i)
        d[i] = std::clamp(glm::dot(n, b[i]), 0.0f, 1.0f);
    if (convention == SsbumpConvention::Valve)
        return d;
    d *= d;
    const float sum = d.x + d.y + d.z;
    return sum > 0.0f ? d / sum : glm::vec3(0.0f);
}

glm::vec3 ssbump_normal(const glm::vec3& w, SsbumpConvention convention)
{
    const auto& b = math::rnm_basis();
    glm::vec3 n(0.0f);
    for (int i = 0; i < 3; ++i)
    {
        const float c = std::max(0.0f, w[i]);
        n += (convention == SsbumpConvention::Valve ? c : std::sqrt(c)) * b[i];
    }
    const float len = glm::length(n);
    return len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
}

namespace
{

void check_field(const HeightField& f, const char* what)
{
    if (f.width == 0 || f.height == 0 || f.heights.size() != size_t(f.width) * f.height)
        throw std::invalid_argument(std::string("hemi: ") + what + ": " + std::to_string(f.heights.size()) +
                                    " heights for a " + std::to_string(f.width) + "x" +
                                    std::to_string(f.height) + " map");
    for (size_t i = 0; i < f.heights.size(); ++i)
        if (!std::isfinite(f.heights[i]))
            throw std::invalid_argument(std::string("hemi: ") + what + ": the height at (" +
                                        std::to_string(i % f.width) + ", " + std::to_string(i / f.width) +
                                        ") is not finite");
}

int64_t wrap_index(int64_t i, int64_t n)
{
    const int64_t m = i % n;
    return m < 0 ? m + n : m;
}

} // namespace

BilateralFilter default_filter(int bits)
{
    return bits <= 8 ? BilateralFilter{2, 0.02f} : BilateralFilter{};
}

HeightField bilateral_filter(const HeightField& field, const BilateralFilter& filter, bool wrap)
{
    check_field(field, "bilateral_filter");
    if (filter.radius < 0 || filter.radius > 64)
        throw std::invalid_argument("hemi: bilateral filter radius " + std::to_string(filter.radius) +
                                    " is not in [0, 64] texels");
    if (!filter.enabled())
        return field;
    if (!(filter.sigma > 0.0f) || !std::isfinite(filter.sigma))
        throw std::invalid_argument("hemi: bilateral filter sigma " + std::to_string(filter.sigma) +
                                    " must be positive (height units)");
    const int r = filter.radius;
    const double sigma_s = 0.5 * r;
    std::vector<double> spatial(size_t(2 * r + 1) * size_t(2 * r + 1));
    for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
            spatial[size_t(dy + r) * size_t(2 * r + 1) + size_t(dx + r)] =
                std::exp(-double(dx * dx + dy * dy) / (2.0 * sigma_s * sigma_s));
    const double range = 1.0 / (2.0 * double(filter.sigma) * double(filter.sigma));
    HeightField out{field.width, field.height, std::vector<float>(field.heights.size())};
    const int64_t w = field.width, h = field.height;
    tbb::parallel_for(int64_t(0), h,
                      [&](int64_t y)
                      {
                          for (int64_t x = 0; x < w; ++x)
                          {
                              const double centre = field.at(uint32_t(x), uint32_t(y));
                              double sum = 0.0, weight = 0.0;
                              for (int dy = -r; dy <= r; ++dy)
                                  for (int dx = -r; dx <= r; ++dx)
                                  {
                                      int64_t sx = x + dx, sy = y + dy;
                                      if (wrap)
                                      {
                                          sx = wrap_index(sx, w);
                                          sy = wrap_index(sy, h);
                                      }
                                      else if (sx < 0 || sy < 0 || sx >= w || sy >= h)
                                          continue;
                                      const double v = field.at(uint32_t(sx), uint32_t(sy));
                                      const double k =
                                          spatial[size_t(dy + r) * size_t(2 * r + 1) + size_t(dx + r)] *
                                          std::exp(-(v - centre) * (v - centre) * range);
                                      sum += k * v;
                                      weight += k;
                                  }
                              out.heights[size_t(y) * size_t(w) + size_t(x)] = float(sum / weight);
                          }
                      });
    return out;
}

std::vector<glm::vec3> height_normals(const HeightField& field, float scale, bool wrap)
{
    check_field(field, "height_normals");
    const int64_t w = field.width, h = field.height;
    std::vector<glm::vec3> out(field.heights.size());
    // The difference of h along an axis: central (over two texels) inside and on a tiling map, one-sided at
    // the borders of one that does not tile; 0 across a map one texel wide.
    auto diff = [&](int64_t x, int64_t y, bool ax) -> double
    {
        const int64_t n = ax ? w : h;
        const int64_t c = ax ? x : y;
        int64_t lo = c - 1, hi = c + 1;
        if (wrap)
        {
            lo = wrap_index(lo, n);
            hi = wrap_index(hi, n);
        }
        else
        {
            lo = std::max<int64_t>(lo, 0);
            hi = std::min<int64_t>(hi, n - 1);
        }
        const double span = wrap ? 2.0 : double(hi - lo);
        if (n == 1 || span == 0.0)
            return 0.0;
        const double a = ax ? field.at(uint32_t(lo), uint32_t(y)) : field.at(uint32_t(x), uint32_t(lo));
        const double b = ax ? field.at(uint32_t(hi), uint32_t(y)) : field.at(uint32_t(x), uint32_t(hi));
        return (b - a) / span;
    };
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < w; ++x)
        {
            const double dx = diff(x, y, true), dv = diff(x, y, false);
            const glm::dvec3 n(-double(scale) * dx, double(scale) * dv, 1.0);
            out[size_t(y) * size_t(w) + size_t(x)] = glm::vec3(glm::normalize(n));
        }
    return out;
}

int ssbump_azimuths(int rays)
{
    // About twice as many azimuths as elevations per azimuth: the horizon varies around z at least as fast
    // as the lobes do along z.
    const int a = int(std::lround(std::sqrt(2.0 * double(rays))));
    return std::clamp(a, 1, std::max(1, rays));
}

namespace
{
// The pieces of ssbump_ray, shared with the bake's loop (which computes each azimuth's angle once).
double azimuth_angle(uint64_t seed, uint64_t texel, int a, int azimuths)
{
    return 2.0 * M_PI * (double(a) + double(uniform01(seed, texel, 0))) / double(azimuths);
}
int rays_in_azimuth(int a, int rays, int azimuths)
{
    return (rays - a + azimuths - 1) / azimuths;
}
double ray_z(uint64_t seed, uint64_t texel, int ray, int azimuths, int in_azimuth)
{
    return (double(ray / azimuths) + double(uniform01(seed, texel, uint64_t(ray) + 1))) / double(in_azimuth);
}
} // namespace

SsbumpRay ssbump_ray(uint64_t seed, uint64_t texel, int ray, int rays)
{
    const int azimuths = ssbump_azimuths(rays);
    const int a = ray % azimuths;
    const int in_azimuth = rays_in_azimuth(a, rays, azimuths);
    const double phi = azimuth_angle(seed, texel, a, azimuths);
    const double z = ray_z(seed, texel, ray, azimuths, in_azimuth);
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    SsbumpRay out;
    out.direction = glm::vec3(float(rho * std::cos(phi)), float(rho * std::sin(phi)), float(z));
    out.weight = float(2.0 * M_PI / double(azimuths) / double(in_azimuth));
    return out;
}

HeightFieldTracer::HeightFieldTracer(const HeightField& field, float scale, bool wrap, float epsilon,
                                     float max_distance)
    : width_(field.width), height_(field.height), wrap_(wrap), epsilon_(epsilon), max_distance_(max_distance)
{
    check_field(field, "HeightFieldTracer");
    if (!(scale > 0.0f) || !std::isfinite(scale))
        throw std::invalid_argument("hemi: height scale " + std::to_string(scale) + " must be positive");
    if (!(epsilon >= 0.0f) || !std::isfinite(epsilon))
        throw std::invalid_argument("hemi: ray epsilon " + std::to_string(epsilon) + " must be >= 0");
    if (!(max_distance > 0.0f) || !std::isfinite(max_distance))
        throw std::invalid_argument("hemi: ray distance " + std::to_string(max_distance) +
                                    " must be positive");
    z_.resize(field.heights.size());
    z_max_ = -std::numeric_limits<float>::infinity();
    for (size_t i = 0; i < z_.size(); ++i)
    {
        z_[i] = scale * field.heights[i];
        if (!std::isfinite(z_[i]))
            throw std::invalid_argument("hemi: height scale " + std::to_string(scale) +
                                        " overflows the heights");
        z_max_ = std::max(z_max_, z_[i]);
    }
    cells_x_ = wrap ? width_ : width_ - 1;
    cells_y_ = wrap ? height_ : height_ - 1;
    if (cells_x_ == 0 || cells_y_ == 0)
        return; // a single row or column without wrapping: no quads, nothing ever blocks
    // Level 0: the highest of each cell's four samples; level L: of each 2^L x 2^L block of cells.
    std::vector<float> level(size_t(cells_x_) * cells_y_);
    for (uint32_t j = 0; j < cells_y_; ++j)
        for (uint32_t i = 0; i < cells_x_; ++i)
        {
            const uint32_t i1 = (i + 1) % width_, j1 = (j + 1) % height_;
            level[size_t(j) * cells_x_ + i] = std::max(std::max(height_at(i, j), height_at(i1, j)),
                                                       std::max(height_at(i, j1), height_at(i1, j1)));
        }
    uint32_t lw = cells_x_, lh = cells_y_;
    mip_.push_back(std::move(level));
    mip_width_.push_back(lw);
    while (lw > 1 || lh > 1)
    {
        const uint32_t nw = (lw + 1) / 2, nh = (lh + 1) / 2;
        const std::vector<float>& prev = mip_.back();
        std::vector<float> next(size_t(nw) * nh, -std::numeric_limits<float>::infinity());
        for (uint32_t j = 0; j < lh; ++j)
            for (uint32_t i = 0; i < lw; ++i)
            {
                float& m = next[size_t(j / 2) * nw + i / 2];
                m = std::max(m, prev[size_t(j) * lw + i]);
            }
        mip_.push_back(std::move(next));
        mip_width_.push_back(nw);
        lw = nw;
        lh = nh;
    }
}

double HeightFieldTracer::horizon(uint32_t x0, uint32_t y0, double tx, double ty, double slope) const
{
    if (mip_.empty())
        return slope;
    const double z0 = double(height_at(x0, y0)) + double(epsilon_);
    const double ox = x0, oy = y0;
    // The walk is in grid coordinates: x along a row, y down the rows (tangent +y is up the image).
    const double dx = tx, dy = -ty;
    const double limit = max_distance_;
    const double inf = std::numeric_limits<double>::infinity();
    const int64_t cx = cells_x_, cy = cells_y_;
    const int64_t step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
    // The cell a coordinate lies in, for a walk going `d` along it: on a grid line, the cell ahead.
    auto cell_of = [](double v, double d)
    {
        double f = std::floor(v);
        if (d < 0 && f == v)
            f -= 1.0;
        return int64_t(f);
    };
    int64_t i = cell_of(ox, dx), j = cell_of(oy, dy);
    if (dx == 0 && !wrap_ && i >= cx)
        i = cx - 1; // along the right border line: its cell is on the left
    if (dy == 0 && !wrap_ && j >= cy)
        j = cy - 1;
    auto next_x = [&](int64_t cell) {
        return dx > 0 ? (double(cell + 1) - ox) / dx : dx < 0 ? (double(cell) - ox) / dx : inf;
    };
    auto next_y = [&](int64_t cell) {
        return dy > 0 ? (double(cell + 1) - oy) / dy : dy < 0 ? (double(cell) - oy) / dy : inf;
    };
    double t_x = next_x(i), t_y = next_y(j);
    const double delta_x = dx != 0 ? 1.0 / std::abs(dx) : inf, delta_y = dy != 0 ? 1.0 / std::abs(dy) : inf;
    const double rise = double(z_max_) - z0; // the most any point can stand above the origin
    double t = 0.0;
    const int levels = int(mip_.size());
    while (true)
    {
        if (rise <= slope * t)
            return slope; // not even the highest point of the map could raise the horizon from here on
        int64_t iw = i, jw = j;
        if (wrap_)
        {
            iw = wrap_index(i, cx);
            jw = wrap_index(j, cy);
        }
        else if (i < 0 || j < 0 || i >= cx || j >= cy)
            return slope; // left the relief over the border
        // Skip the largest block around the cell that cannot raise the horizon: every point of it ahead lies
        // at distance >= t and no higher than its maximum.
        bool skipped = false;
        for (int L = levels - 1; L >= 0; --L)
        {
            const int64_t bi = iw >> L, bj = jw >> L;
            if (double(mip_[size_t(L)][size_t(bj) * mip_width_[size_t(L)] + size_t(bi)]) - z0 > slope * t)
                continue;
            const int64_t x_lo = i - iw + (bi << L), x_hi = std::min(x_lo + (int64_t(1) << L), i - iw + cx);
            const int64_t y_lo = j - jw + (bj << L), y_hi = std::min(y_lo + (int64_t(1) << L), j - jw + cy);
            const double ex = dx > 0 ? (double(x_hi) - ox) / dx : dx < 0 ? (double(x_lo) - ox) / dx : inf;
            const double ey = dy > 0 ? (double(y_hi) - oy) / dy : dy < 0 ? (double(y_lo) - oy) / dy : inf;
            t = std::min(ex, ey);
            if (t >= limit)
                return slope;
            if (ex <= ey)
            {
                i = dx > 0 ? x_hi : x_lo - 1;
                j = ey == ex ? (dy > 0 ? y_hi : y_lo - 1)
                             : std::clamp(cell_of(oy + dy * t, dy), y_lo, y_hi - 1);
            }
            else
            {
                j = dy > 0 ? y_hi : y_lo - 1;
                i = std::clamp(cell_of(ox + dx * t, dx), x_lo, x_hi - 1);
            }
            t_x = next_x(i);
            t_y = next_y(j);
            skipped = true;
            break;
        }
        if (skipped)
            continue;
        // The cell's polyline vertices: where the line crosses its diagonal and where it leaves it.
        const uint32_t i0 = uint32_t(iw), j0 = uint32_t(jw);
        const uint32_t i1 = (i0 + 1) % width_, j1 = (j0 + 1) % height_;
        const double h00 = height_at(i0, j0), h10 = height_at(i1, j0), h01 = height_at(i0, j1),
                     h11 = height_at(i1, j1);
        const double t_exit = std::min(t_x, t_y);
        const double t_end = std::min(t_exit, limit);
        auto visit = [&](double s)
        {
            const double fx = std::clamp(ox + dx * s - double(i), 0.0, 1.0);
            const double fy = std::clamp(oy + dy * s - double(j), 0.0, 1.0);
            // Triangle (x, y), (x + 1, y), (x + 1, y + 1) where fx >= fy; (x, y), (x, y + 1), (x + 1, y + 1)
            // else.
            const double hz = fx >= fy ? h00 + fx * (h10 - h00) + fy * (h11 - h10)
                                       : h00 + fy * (h01 - h00) + fx * (h11 - h01);
            slope = std::max(slope, (hz - z0) / s);
        };
        if (dx != dy)
        {
            const double s = (double(i - j) - (ox - oy)) / (dx - dy);
            if (s > t && s < t_end)
                visit(s);
        }
        if (t_end > 0.0)
            visit(t_end);
        if (t_exit >= limit)
            return slope;
        t = t_exit;
        if (t_x < t_y)
        {
            i += step_x;
            t_x += delta_x;
        }
        else if (t_y < t_x)
        {
            j += step_y;
            t_y += delta_y;
        }
        else
        {
            i += step_x;
            j += step_y;
            t_x += delta_x;
            t_y += delta_y;
        }
    }
}

bool HeightFieldTracer::occluded(uint32_t x, uint32_t y, const glm::vec3& d) const
{
    const double rho = std::sqrt(double(d.x) * d.x + double(d.y) * d.y);
    if (rho == 0.0 || !(d.z > 0.0f))
        return false; // straight up nothing blocks a height field (and z <= 0 is not asked)
    const double k = double(d.z) / rho;
    return k < horizon(x, y, double(d.x) / rho, double(d.y) / rho, k);
}

io::Mesh height_field_mesh(const HeightField& field, float scale)
{
    check_field(field, "height_field_mesh");
    io::Mesh mesh;
    const uint32_t w = field.width, h = field.height;
    mesh.positions.reserve(field.heights.size());
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x)
            mesh.positions.emplace_back(float(x), -float(y), scale * field.at(x, y));
    for (uint32_t y = 0; y + 1 < h; ++y)
        for (uint32_t x = 0; x + 1 < w; ++x)
        {
            const uint32_t a = y * w + x, b = a + 1, c = a + w, d = c + 1;
            // Counter-clockwise seen from +z (tangent +y is up, rows go down): (a, d, b) and (a, c, d).
            mesh.indices.insert(mesh.indices.end(), {a, d, b, a, c, d});
        }
    return mesh;
}

void check_ssbump_options(const SsbumpOptions& o)
{
    if (!(o.scale > 0.0f) || !std::isfinite(o.scale))
    {
        char text[32];
        std::snprintf(text, sizeof text, "%g", double(o.scale));
        throw std::invalid_argument(std::string("height scale ") + text +
                                    " must be positive and finite (texel widths per height unit)");
    }
    if (o.rays < 1 || o.rays > (1 << 20))
        throw std::invalid_argument("rays per texel " + std::to_string(o.rays) + " is not in [1, 2^20]");
    if (!(o.epsilon >= 0.0f) || !std::isfinite(o.epsilon))
        throw std::invalid_argument("ray epsilon " + std::to_string(o.epsilon) + " must be >= 0");
    if (!(o.max_distance >= 0.0f) || !std::isfinite(o.max_distance))
        throw std::invalid_argument("ray distance " + std::to_string(o.max_distance) + " must be >= 0");
    if (o.filter.radius < 0 || o.filter.radius > 64 || (o.filter.enabled() && !(o.filter.sigma > 0.0f)))
        throw std::invalid_argument("bilateral filter " + std::to_string(o.filter.radius) + "," +
                                    std::to_string(o.filter.sigma) +
                                    ": the radius must be in [0, 64] texels and sigma positive");
}

namespace
{
constexpr uint64_t kSsbumpCheckpointVersion = 1;

uint64_t ssbump_key(const HeightField& f, const SsbumpOptions& o)
{
    CheckpointKey key(kSsbumpCheckpointVersion);
    key.add_value(f.width).add_value(f.height).add_array(std::span<const float>(f.heights));
    key.add_value(o.scale).add_value(o.rays).add_value(o.occlusion).add_value(o.wrap);
    key.add_value(int(o.convention)).add_value(o.filter.radius).add_value(o.filter.sigma).add_value(o.seed);
    key.add_value(o.epsilon).add_value(o.max_distance);
    return key.digest();
}
} // namespace

uint64_t ssbump_memory(uint64_t texels, const SsbumpOptions& o)
{
    // Per texel: the decoded RGBA float image (16), heights and their filtered copy (8), normals, occlusion
    // and weights (36), the 8-bit output and its PNG (4), the horizon tracer's tables (4). Measured at
    // 2048^2 with occlusion: 54 bytes per texel at the peak (the image is freed before the bake grows).
    const uint64_t per_texel = 16 + 8 + 36 + 4 + (o.occlusion ? 4 : 0);
    return texels > UINT64_MAX / per_texel ? UINT64_MAX : texels * per_texel;
}

SsbumpMap bake_ssbump(const HeightField& input, const SsbumpOptions& o,
                      const std::function<void(const SsbumpProgress&)>& progress)
{
    check_field(input, "bake_ssbump");
    check_ssbump_options(o);
    const HeightField field = bilateral_filter(input, o.filter, o.wrap);
    SsbumpMap out;
    out.width = field.width;
    out.height = field.height;
    out.convention = o.convention;
    out.normals = height_normals(field, o.scale, o.wrap);
    const size_t n = field.heights.size();
    out.occlusion.assign(n, glm::vec3(1.0f));
    out.weights.resize(n);
    auto finish = [&]()
    {
        for (size_t t = 0; t < n; ++t)
            out.weights[t] = ssbump_weights(out.normals[t], o.convention) * out.occlusion[t];
    };
    if (!o.occlusion)
    {
        finish();
        return out;
    }
    const float distance =
        o.max_distance > 0.0f ? o.max_distance : float(std::max(field.width, field.height));
    const HeightFieldTracer tracer(field, o.scale, o.wrap, o.epsilon, distance);
    const auto& basis = math::rnm_basis();
    const int azimuths = ssbump_azimuths(o.rays);
    // The lobes' normalisation does not depend on visibility: the ratio estimator's denominator uses the same
    // rays, so a texel that sees everything gets exactly 1.
    auto texel = [&](uint32_t x, uint32_t y, std::vector<double>& z)
    {
        const uint64_t index = uint64_t(y) * field.width + x;
        double seen[3] = {0, 0, 0}, all[3] = {0, 0, 0};
        for (int a = 0; a < azimuths; ++a)
        {
            // The rays of azimuth a share its direction around z: one horizon search answers them all.
            const int in_azimuth = rays_in_azimuth(a, o.rays, azimuths);
            const double phi = azimuth_angle(o.seed, index, a, azimuths);
            const double c = std::cos(phi), s = std::sin(phi);
            z.resize(size_t(in_azimuth));
            double z_min = 1.0;
            for (int e = 0; e < in_azimuth; ++e)
            {
                z[size_t(e)] = ray_z(o.seed, index, a + e * azimuths, azimuths, in_azimuth);
                z_min = std::min(z_min, z[size_t(e)]);
            }
            const double horizon =
                z_min < 1.0 ? tracer.horizon(x, y, c, s, z_min / std::sqrt(1.0 - z_min * z_min)) : 0.0;
            const double weight = 2.0 * M_PI / double(azimuths) / double(in_azimuth);
            for (int e = 0; e < in_azimuth; ++e)
            {
                const double rho = std::sqrt(std::max(0.0, 1.0 - z[size_t(e)] * z[size_t(e)]));
                const bool visible = rho == 0.0 || z[size_t(e)] / rho >= horizon;
                for (int i = 0; i < 3; ++i)
                {
                    const glm::vec3& b = basis[size_t(i)];
                    const double lobe = std::max(0.0, double(b.x) * rho * c + double(b.y) * rho * s +
                                                          double(b.z) * z[size_t(e)]) *
                                        weight;
                    all[i] += lobe;
                    if (visible)
                        seen[i] += lobe;
                }
            }
        }
        glm::vec3& occ = out.occlusion[index];
        for (int i = 0; i < 3; ++i)
            occ[i] = all[i] > 0.0 ? float(seen[i] / all[i]) : 1.0f;
    };

    Distribution& dist = o.distribution ? *o.distribution : local_distribution();
    const uint64_t key = ssbump_key(input, o);
    dist.check_same(key, "baked an SSBump map whose height map or options");
    SliceCheckpoint checkpoint(
        dist.leader() ? o.checkpoint : std::filesystem::path(), key, 1, uint32_t(field.height),
        {{"occlusion", std::as_writable_bytes(std::span<glm::vec3>(out.occlusion))}}, o.checkpoint_seconds);
    uint32_t row = 0;
    if (const std::optional<SlicePosition> resumed = checkpoint.resume(dist)) // every rank from the leader's
    {
        row = resumed->next_item;
        out.resumed = true;
    }
    // Slices of about 2^22 rays: progress and checkpoints between them, on this thread.
    const uint32_t slice_rows = uint32_t(std::clamp<uint64_t>(
        (uint64_t(1) << 22) / (uint64_t(field.width) * uint64_t(o.rays)), 1, field.height));
    const uint64_t texels = uint64_t(n);
    if (progress && dist.leader())
        progress({uint64_t(row) * field.width, texels, checkpoint.error()});
    const auto trace0 = std::chrono::steady_clock::now();
    // A row's work writes its texels' occlusion, which every rank gathers.
    const ItemArray rows[1] = {
        {reinterpret_cast<std::byte*>(out.occlusion.data()), sizeof(glm::vec3) * size_t(field.width)}};
    dist.run(
        row, field.height, slice_rows, rows,
        [&](uint32_t begin, uint32_t end)
        {
            tbb::parallel_for(tbb::blocked_range<uint32_t>(begin, end, 1),
                              [&](const tbb::blocked_range<uint32_t>& r)
                              {
                                  std::vector<double> z;
                                  for (uint32_t y = r.begin(); y != r.end(); ++y)
                                      for (uint32_t x = 0; x < field.width; ++x)
                                          texel(x, y, z);
                              });
        },
        [&](uint32_t next)
        {
            checkpoint.slice_done(0, next);
            if (progress)
                progress({uint64_t(next) * field.width, texels, checkpoint.error()});
        });
    out.rays += uint64_t(field.height - std::min(row, field.height)) * field.width * uint64_t(o.rays);
    if (progress && dist.leader())
        progress({texels, texels, checkpoint.error()});
    out.trace_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - trace0).count();
    out.checkpoint_error = checkpoint.error();
    finish();
    return out;
}

SsbumpMap ssbump_from_normals(uint32_t width, uint32_t height, std::span<const glm::vec3> normals,
                              SsbumpConvention convention)
{
    if (width == 0 || height == 0 || normals.size() != size_t(width) * height)
        throw std::invalid_argument("hemi: ssbump_from_normals: " + std::to_string(normals.size()) +
                                    " normals for a " + std::to_string(width) + "x" + std::to_string(height) +
                                    " map");
    SsbumpMap out;
    out.width = width;
    out.height = height;
    out.convention = convention;
    out.normals.assign(normals.begin(), normals.end());
    out.occlusion.assign(normals.size(), glm::vec3(1.0f));
    out.weights.resize(normals.size());
    for (size_t i = 0; i < normals.size(); ++i)
        out.weights[i] = ssbump_weights(normals[i], convention);
    return out;
}

HeightChannel parse_height_channel(std::string_view name)
{
    if (name == "grey" || name == "gray")
        return HeightChannel::Grey;
    if (name == "r")
        return HeightChannel::R;
    if (name == "g")
        return HeightChannel::G;
    if (name == "b")
        return HeightChannel::B;
    if (name == "a")
        return HeightChannel::A;
    throw std::invalid_argument("unknown height channel '" + std::string(name) +
                                "' (known: grey, r, g, b, a)");
}

namespace
{

// Whether RGB reads as a tangent-space normal map: most texels decode (2 c - 1) to near-unit vectors facing
// +z, and they are not all the same grey.
bool looks_like_normal_map(const io::DataImage& image)
{
    size_t unit = 0, grey = 0;
    const size_t n = size_t(image.width) * image.height;
    for (size_t i = 0; i < n; ++i)
    {
        const glm::vec3 v(2.0f * image.rgba(i, 0) - 1.0f, 2.0f * image.rgba(i, 1) - 1.0f,
                          2.0f * image.rgba(i, 2) - 1.0f);
        if (std::abs(glm::length(v) - 1.0f) < 0.1f && v.z > 0.2f)
            ++unit;
        if (image.rgba(i, 0) == image.rgba(i, 1) && image.rgba(i, 1) == image.rgba(i, 2))
            ++grey;
    }
    return unit >= n * 9 / 10 && grey < n / 2;
}

} // namespace

HeightMapFile read_height_map(const std::filesystem::path& path, HeightChannel channel)
{
    const io::DataImage image = io::read_data_image(path);
    const std::string name = path.string();
    const bool exr = image.bits == 32;
    const size_t n = size_t(image.width) * image.height;
    const bool has_alpha = exr || image.channels == 2 || image.channels == 4;
    const bool has_colour = exr || image.channels >= 3;
    bool rgb_equal = true;
    for (size_t i = 0; i < n && rgb_equal; ++i)
    {
        rgb_equal = image.rgba(i, 0) == image.rgba(i, 1) && image.rgba(i, 1) == image.rgba(i, 2);
    }
    int source = 0;
    switch (channel)
    {
    case HeightChannel::Grey:
        if (has_colour && !rgb_equal)
        {
            if (looks_like_normal_map(image))
                throw io::FormatError(name +
                                      ": this looks like a tangent-space normal map (its texels decode to "
                                      "unit vectors facing +z), not a height map; convert one with "
                                      "`hemi-bake ssbump --from-normal`");
            bool single_r = exr;
            for (size_t i = 0; i < n && single_r; ++i)
                single_r = image.rgba(i, 1) == 0.0f && image.rgba(i, 2) == 0.0f;
            if (!single_r)
                throw io::FormatError(name + ": a colour image, not a grey height map; choose the channel "
                                             "that holds the heights with --channel r|g|b|a");
        }
        source = 0;
        break;
    case HeightChannel::R:
        source = 0;
        break;
    case HeightChannel::G:
        source = 1;
        break;
    case HeightChannel::B:
        source = 2;
        break;
    case HeightChannel::A:
        if (!has_alpha)
            throw io::FormatError(name + ": --channel a, but the image has no alpha channel");
        source = 3;
        break;
    }
    if (!has_colour && (channel == HeightChannel::G || channel == HeightChannel::B))
        source = 0; // a grey PNG's only channel
    HeightMapFile out;
    out.bits = image.bits;
    out.field.width = image.width;
    out.field.height = image.height;
    out.field.heights.resize(n);
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (size_t i = 0; i < n; ++i)
    {
        const float v = image.rgba(i, source);
        if (!std::isfinite(v))
            throw io::FormatError(name + ": the height at (" + std::to_string(i % image.width) + ", " +
                                  std::to_string(i / image.width) + ") is not finite");
        out.field.heights[i] = v;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    if (source == 3 && lo == hi)
        throw io::FormatError(name + ": --channel a, but the alpha channel is constant (" +
                              std::to_string(lo) + "): it holds no heights");
    if (has_alpha && source != 3 && !exr)
    {
        out.alpha.resize(n);
        for (size_t i = 0; i < n; ++i)
            out.alpha[i] = uint8_t(std::lround(std::clamp(image.rgba(i, 3), 0.0f, 1.0f) * 255.0f));
    }
    return out;
}

std::vector<glm::vec3> read_normal_map(const std::filesystem::path& path, uint32_t& width, uint32_t& height,
                                       std::vector<uint8_t>& alpha, size_t* zero_normals)
{
    const io::DataImage image = io::read_data_image(path);
    const std::string name = path.string();
    if (image.bits == 32)
        throw io::FormatError(name + ": a normal map must be a PNG (n * 0.5 + 0.5 in RGB)");
    if (image.channels < 3 || !looks_like_normal_map(image))
        throw io::FormatError(name +
                              ": does not look like a tangent-space normal map (most texels must decode, "
                              "as 2 c - 1, to unit vectors facing +z)");
    width = image.width;
    height = image.height;
    const size_t n = size_t(width) * height;
    std::vector<glm::vec3> out(n);
    size_t zeros = 0;
    for (size_t i = 0; i < n; ++i)
    {
        const glm::vec3 v(2.0f * image.rgba(i, 0) - 1.0f, 2.0f * image.rgba(i, 1) - 1.0f,
                          2.0f * image.rgba(i, 2) - 1.0f);
        const float len = glm::length(v);
        if (len < 1e-3f)
        {
            ++zeros;
            out[i] = glm::vec3(0.0f, 0.0f, 1.0f);
        }
        else
            out[i] = v / len;
    }
    alpha.clear();
    if (image.channels == 4)
    {
        alpha.resize(n);
        for (size_t i = 0; i < n; ++i)
            alpha[i] = uint8_t(std::lround(std::clamp(image.rgba(i, 3), 0.0f, 1.0f) * 255.0f));
    }
    if (zero_normals)
        *zero_normals = zeros;
    return out;
}

std::vector<uint8_t> ssbump_rgba8(std::span<const glm::vec3> values, std::span<const uint8_t> alpha,
                                  bool signed_normal)
{
    if (!alpha.empty() && alpha.size() != values.size())
        throw std::invalid_argument("hemi: ssbump_rgba8: " + std::to_string(alpha.size()) +
                                    " alpha values for " + std::to_string(values.size()) + " texels");
    std::vector<uint8_t> out(values.size() * 4);
    for (size_t i = 0; i < values.size(); ++i)
    {
        for (int c = 0; c < 3; ++c)
        {
            const float v = signed_normal ? values[i][c] * 0.5f + 0.5f : values[i][c];
            out[i * 4 + size_t(c)] = uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
        }
        out[i * 4 + 3] = alpha.empty() ? 255 : alpha[i];
    }
    return out;
}

} // namespace hemi::bake
