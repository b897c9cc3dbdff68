// The directional lightmap bake (lightmap_bake.h).
#include "light_sampler.h"
#include "texel_origin.h"

#include <hemi/bake/checkpoint.h>
#include <hemi/bake/embree_scene.h>
#include <hemi/bake/lightmap_bake.h>
#include <hemi/bake/ray_generator.h>
#include <hemi/bake/reflection_probe.h>
#include <hemi/io/image.h>
#include <hemi/math/basis.h>
#include <hemi/math/luminance.h>
#include <hemi/math/rnm_basis.h>
#include <hemi/math/sh.h>
#include <hemi/math/sh_environment.h>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace hemi::bake
{

glm::vec3 LightmapLights::environment_radiance(const glm::vec3& scene_d) const
{
    if (environment.pixels.empty())
        return uniform;
    const glm::vec3 d = scene_to_world * scene_d;
    // Piecewise constant over the pixels (what math::project_equirect integrates, and what the importance
    // sampler's density is proportional to).
    uint32_t x = 0, y = 0;
    math::equirect_pixel(glm::dvec3(d), environment.width, environment.height, x, y);
    const float* p = environment.at(x, y);
    return glm::vec3(p[0], p[1], p[2]) * environment_scale;
}

LightmapSurfaces::LightmapSurfaces(const io::Mesh& mesh, const std::vector<io::Material>& materials,
                                   const std::vector<io::EncodedImage>& images,
                                   const std::vector<io::Primitive>& primitives)
    : mesh_(&mesh), materials_(materials)
{
    if (materials_.empty())
        materials_.emplace_back(); // glTF's default material
    for (const io::EncodedImage& image : images)
        images_.push_back(io::decode_image(image));
    const size_t triangles = mesh.indices.size() / 3;
    material_of_.assign(triangles, 0);
    for (const io::Primitive& p : primitives)
    {
        if (p.material >= materials_.size() || (p.first_index + p.index_count) / 3 > triangles)
            throw std::invalid_argument("hemi: a primitive's range or material is out of range");
        for (uint32_t t = p.first_index / 3; t < (p.first_index + p.index_count) / 3; ++t)
            material_of_[t] = p.material;
    }
    for (const io::Material& m : materials_)
    {
        for (const io::TextureRef* t : {&m.base_color, &m.emissive, &m.normal})
            if (t->present() && size_t(t->image) >= images_.size())
                throw std::invalid_argument("hemi: material '" + m.name + "' uses image " +
                                            std::to_string(t->image) + " of " +
                                            std::to_string(images_.size()));
        emissive_ = emissive_ || m.emissive_factor != glm::vec3(0.0f);
    }
}

glm::vec4 LightmapSurfaces::sample(const io::TextureRef& t, uint32_t triangle, float bu, float bv,
                                   bool srgb) const
{
    if (!t.present())
        return glm::vec4(1.0f);
    const std::vector<glm::vec2>& set = t.texcoord == 1 ? mesh_->uvs1 : mesh_->uvs;
    if (set.empty())
        return glm::vec4(1.0f);
    const uint32_t* idx = &mesh_->indices[size_t(triangle) * 3];
    const glm::vec2 uv = (1.0f - bu - bv) * set[idx[0]] + bu * set[idx[1]] + bv * set[idx[2]];
    const glm::vec2 st = glm::vec2(t.uv_transform() * glm::vec3(uv, 1.0f));
    const io::ImageRgba8& im = images_[size_t(t.image)];
    auto wrap = [](int64_t i, int64_t n, io::Wrap mode)
    {
        if (mode == io::Wrap::ClampToEdge)
            return std::clamp<int64_t>(i, 0, n - 1);
        if (mode == io::Wrap::MirroredRepeat)
        {
            const int64_t period = 2 * n, m = ((i % period) + period) % period;
            return m < n ? m : period - 1 - m;
        }
        return ((i % n) + n) % n;
    };
    const double fx = double(st.x) * im.width - 0.5, fy = double(st.y) * im.height - 0.5;
    const double x0 = std::floor(fx), y0 = std::floor(fy);
    const float tx = float(fx - x0), ty = float(fy - y0);
    auto texel = [&](int64_t x, int64_t y)
    {
        const uint8_t* p = &im.pixels[(size_t(wrap(y, im.height, t.sampler.wrap_t)) * im.width +
                                       size_t(wrap(x, im.width, t.sampler.wrap_s))) *
                                      4];
        // sRGB's curve through a table of its 256 values (the same floats as io::srgb_eotf(p / 255), without
        // twelve powf calls a lookup).
        static const std::array<float, 256> linear = []
        {
            std::array<float, 256> table{};
            for (size_t i = 0; i < table.size(); ++i)
                table[i] = io::srgb_eotf(float(i) / 255.0f);
            return table;
        }();
        if (srgb)
            return glm::vec4(linear[p[0]], linear[p[1]], linear[p[2]], p[3] / 255.0f);
        return glm::vec4(p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f, p[3] / 255.0f);
    };
    const int64_t ix = int64_t(x0), iy = int64_t(y0);
    const glm::vec4 top = texel(ix, iy) * (1.0f - tx) + texel(ix + 1, iy) * tx;
    const glm::vec4 bottom = texel(ix, iy + 1) * (1.0f - tx) + texel(ix + 1, iy + 1) * tx;
    return top * (1.0f - ty) + bottom * ty;
}

glm::vec3 LightmapSurfaces::albedo(uint32_t triangle, float u, float v) const
{
    const io::Material& m = materials_[material_of_[triangle]];
    return glm::vec3(m.base_color_factor) * glm::vec3(sample(m.base_color, triangle, u, v, true));
}

glm::vec3 LightmapSurfaces::emission(uint32_t triangle, float u, float v) const
{
    const io::Material& m = materials_[material_of_[triangle]];
    if (m.emissive_factor == glm::vec3(0.0f))
        return glm::vec3(0.0f);
    return m.emissive_factor * glm::vec3(sample(m.emissive, triangle, u, v, true));
}

glm::vec3 LightmapSurfaces::tangent_normal(uint32_t triangle, float u, float v) const
{
    const io::Material& m = materials_[material_of_[triangle]];
    if (!m.normal.present())
        return glm::vec3(0.0f, 0.0f, 1.0f);
    const glm::vec3 c = glm::vec3(sample(m.normal, triangle, u, v, false)) * 2.0f - 1.0f;
    const glm::vec3 n(c.x * m.normal_scale, c.y * m.normal_scale, c.z);
    const float length = glm::length(n);
    return length > 0.0f ? n / length : glm::vec3(0.0f, 0.0f, 1.0f);
}

bool LightmapSurfaces::double_sided(uint32_t triangle) const
{
    return materials_[material_of_[triangle]].double_sided;
}

namespace
{

// 7: the mixed lights' shadowmask and direct light; 8: the rays' angles from a table of turns, the sums in
// float, the bounces' lookups of a packed map; 9: in tiles, the mixed lights' values in the tile file.
constexpr uint64_t kLightmapCheckpointVersion = 9;

void check(const LightmapLights& l, const LightmapBakeOptions& o)
{
    if (o.rays < 1 || o.rays > (1 << 20))
        throw std::invalid_argument("rays per texel " + std::to_string(o.rays) + " is not in [1, 2^20]");
    if (o.sun_rays < 1 || o.sun_rays > (1 << 16))
        throw std::invalid_argument("sun rays per texel " + std::to_string(o.sun_rays) +
                                    " is not in [1, 65536]");
    if (!(o.ray_offset >= 0.0f) || !std::isfinite(o.ray_offset))
        throw std::invalid_argument("the ray offset must be >= 0");
    if (o.bounces < 0 || o.bounces > 16)
        throw std::invalid_argument("bounces " + std::to_string(o.bounces) + " is not in [0, 16]");
    detail::check_lights(l);
    shadowmask_channels(l); // throws for a fifth overlapping mixed light
}

uint64_t key_of(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapLights& l,
                const LightmapBakeOptions& o, const LightmapSurfaces* surfaces,
                std::span<const io::Material> materials, bool tiled)
{
    CheckpointKey key(kLightmapCheckpointVersion);
    key.add_array(std::span<const glm::vec3>(mesh.positions))
        .add_array(std::span<const uint32_t>(mesh.indices));
    key.add_array(std::span<const glm::vec2>(mesh.uvs1)).add_array(std::span<const glm::vec3>(mesh.normals));
    key.add_array(std::span<const glm::vec4>(mesh.tangents));
    key.add_value(atlas.width).add_value(atlas.height);
    key.add_value(l.uniform).add_value(l.environment.width).add_value(l.environment.height);
    key.add_array(std::span<const float>(l.environment.pixels)).add_value(l.environment_scale);
    key.add_value(l.sun)
        .add_value(l.sun_direction)
        .add_value(l.sun_irradiance)
        .add_value(l.sun_diameter_degrees)
        .add_value(int(l.sun_mode));
    key.add_value(l.scene_to_world);
    for (const io::PunctualLight& p : l.punctual)
        key.add_value(int(p.type))
            .add_value(p.color)
            .add_value(p.intensity)
            .add_value(p.range)
            .add_value(p.inner_cone)
            .add_value(p.outer_cone)
            .add_value(p.position)
            .add_value(p.direction)
            .add_value(int(p.mode));
    key.add_value(o.rays)
        .add_value(o.sun_rays)
        .add_value(o.seed)
        .add_value(o.ray_offset)
        .add_value(o.bounces)
        .add_value(o.keep_noise)
        .add_value(2)      // the denoiser's noise: 2, estimated from neighbouring samples (1: two halves)
        .add_value(tiled); // the checkpoint's sections differ (the sums are in the tile file)
    key.add_value(EmbreeScene::embree_version()).add_value(surfaces != nullptr);
    for (const io::Material& m : materials)
        key.add_value(m.base_color_factor).add_value(m.emissive_factor).add_value(m.double_sided);
    if (surfaces)
        for (const io::ImageRgba8& im : surfaces->images())
            key.add_array(std::span<const uint8_t>(im.pixels));
    return key.digest();
}

} // namespace

namespace
{
// Per texel values spread over the atlas: covered texels hold theirs, empty ones within `dilate` texels of a
// chart the mean of their filled 8-neighbours (one ring per pass), the rest 0. A texel inside geometry
// (valid 0) is filled like an empty one from valid texels; where none reaches it within `dilate` rings it
// keeps its own value, and the empty texels around it take that as they take a valid texel's (a face no
// viewer reaches keeps the light it sees, as a reference renderer shows it). K values a texel. Only the
// blocks that hold a covered texel or one within `dilate` texels of one are stored, so the maps' memory
// follows the covered texels.
// `produce(first, values)` gives the K values of texels [first, first + values.size() / K), asked for in
// order, a chunk at a time: a map is filled without all of its texels' values in memory at once.
// The texels are given by their places in a width x height atlas: place(i) is texel i's (x, y).
using TexelValues = std::function<void(uint32_t first, std::span<glm::vec3> values)>;
// Texel i's chart (LightmapTexels::chart); empty: no charts.
using TexelChart = std::function<uint32_t(uint32_t i)>;

// The bake's tile file (texel_file.h): per texel the sums of the passes (SH9, then plain's and rnm's), the
// pass's irradiance at the normal that the next pass's bounce map is made from, the texel's ray origin and
// whether it was moved out of a wall (copy 0 alone), and with keep_noise the noise estimate.
constexpr size_t kBounceField = 2, kOriginField = 3, kMovedField = 4, kNoiseField = 5;
// The bounce map: dilated by two texels, in bands of at most 2^20 slots (and at least a tile's, or 1024).
constexpr int kBounceDilation = 2;
constexpr size_t kBounceBandSlots = size_t(1) << 20, kBounceBandLeastSlots = 1024;
// An invalid texel (inside geometry, `valid`) is filled only from valid texels of its own chart (`chart`,
// per texel; empty: any): a texel that the 32-ray test judged inside geometry though a viewer sees it (a
// ceiling of a sealed level, whose rays meet many backs) keeps its own value beside another face's
// rectangle in an unpadded page, instead of taking that face's light (issue 41: oacmpdm1's ceiling at
// Quake (619, -551, 384), 0 against the reference's 0.117).
// The blocks a dilation by `dilate` texels keeps: those that hold a covered texel or one within `dilate`
// texels of one.
template <typename Place>
io::BlockGrid dilated_grid(uint32_t width, uint32_t height, uint32_t n, const Place& place, int dilate)
{
    dilate = std::max(dilate, 0);
    const int64_t w = width, h = height, B = io::BlockGrid::kSize;
    const int64_t bx = (w + B - 1) / B, by = (h + B - 1) / B;
    std::vector<uint8_t> keep(size_t(bx * by), 0);
    for (uint32_t texel = 0; texel < n; ++texel)
    {
        const glm::uvec2 t = place(texel);
        for (int64_t j = std::max<int64_t>(0, int64_t(t.y) - dilate) / B;
             j <= std::min<int64_t>(h - 1, int64_t(t.y) + dilate) / B; ++j)
            for (int64_t i = std::max<int64_t>(0, int64_t(t.x) - dilate) / B;
                 i <= std::min<int64_t>(w - 1, int64_t(t.x) + dilate) / B; ++i)
                keep[size_t(j * bx + i)] = 1;
    }
    std::vector<uint32_t> blocks;
    for (size_t i = 0; i < keep.size(); ++i)
        if (keep[i])
            blocks.push_back(uint32_t(i));
    return io::BlockGrid(width, height, std::move(blocks));
}

// The dilation of `grid` (dilated_grid's) made band by band: bands of whole block rows of at most
// `band_slots` slots each (at least one row), each dilated with the rows within `dilate` texels above and
// below it (whole block rows), as far as a texel's dilated value depends on others, so that each band's
// values come out as the whole atlas's would. next() makes the next band: `maps` over the band and its rows
// around, whose blocks [at, at + count) are grid's blocks [first, first + count). The texels must come in the
// atlas's order (block row after block row); `produce` is then asked for the texels of each band and its rows
// around (those are asked for again with the next band). With band_slots at least grid.slots(), one band:
// the whole atlas, each texel asked for once. An atlas whose texels are not in that order is one band.
class BandDilation
{
  public:
    struct Band
    {
        io::BlockMaps maps;
        uint32_t first = 0, count = 0, at = 0;
    };

    BandDilation(io::BlockGrid grid, uint32_t n, std::function<glm::uvec2(uint32_t)> place, int k, int dilate,
                 std::span<const uint8_t> valid, TexelChart chart, size_t band_slots)
        : grid_(std::move(grid)), n_(n), place_(std::move(place)), k_(k), dilate_(std::max(dilate, 0)),
          valid_(valid), chart_(std::move(chart)), band_slots_(band_slots)
    {
        const uint32_t B = io::BlockGrid::kSize, bx = grid_.blocks_x();
        by_ = grid_.blocks_y();
        const std::vector<uint32_t>& all = grid_.blocks();
        // Per block row r: the first of grid's blocks and the first texel in it or a later row.
        row_block_.assign(size_t(by_) + 1, 0);
        row_texel_.assign(size_t(by_) + 1, n);
        for (uint32_t r = 0, b = 0; r <= by_; ++r)
        {
            while (b < all.size() && all[b] / bx < r)
                ++b;
            row_block_[r] = b;
        }
        bool ordered = true;
        for (uint32_t i = n; i-- > 0;)
        {
            const uint32_t row = place_(i).y / B;
            row_texel_[row] = i;
            ordered = ordered && (i == 0 || place_(i - 1).y / B <= row);
        }
        for (uint32_t r = by_; r-- > 0;)
            row_texel_[r] = std::min(row_texel_[r], row_texel_[r + 1]);
        if (!ordered)
            band_slots_ = SIZE_MAX;
        halo_ = uint32_t((dilate_ + int(B) - 1) / int(B));
    }
    const io::BlockGrid& grid() const { return grid_; }
    void restart() { r0_ = 0; }
    // While next() asks for values: the texels of the band's own rows, [first, second) (the others are the
    // rows around it, asked for again with the next band).
    std::pair<uint32_t, uint32_t> own_texels() const { return own_; }

    bool next(const TexelValues& produce, Band& band)
    {
        if (r0_ >= by_)
            return false;
        const bool whole = band_slots_ == SIZE_MAX;
        const auto lo = [&](uint32_t r) { return whole ? 0u : r >= halo_ ? r - halo_ : 0u; };
        const auto hi = [&](uint32_t r) { return whole ? by_ : std::min(by_, r + halo_); };
        // Rows [r0, r1) out of this band, [lo(r0), hi(r1)) dilated for it.
        uint32_t r1 = whole ? by_ : r0_ + 1;
        while (r1 < by_ &&
               size_t(row_block_[hi(r1 + 1)] - row_block_[lo(r0_)]) * io::BlockGrid::kTexels <= band_slots_)
            ++r1;
        const uint32_t first_row = lo(r0_), last_row = hi(r1);
        const std::vector<uint32_t>& all = grid_.blocks();
        band.maps = io::BlockMaps(io::BlockGrid(grid_.width(), grid_.height(),
                                                std::vector<uint32_t>(all.begin() + row_block_[first_row],
                                                                      all.begin() + row_block_[last_row])),
                                  uint32_t(k_));
        own_ = {whole ? 0 : row_texel_[r0_], whole ? n_ : row_texel_[r1]};
        dilate(band.maps, whole ? 0 : row_texel_[first_row], whole ? n_ : row_texel_[last_row], produce);
        band.first = whole ? 0 : row_block_[r0_];
        band.count = (whole ? uint32_t(all.size()) : row_block_[r1]) - band.first;
        band.at = band.first - row_block_[first_row];
        r0_ = r1;
        return true;
    }

  private:
    // Texels [t0, t1) into `maps` (over their blocks), then the dilation.
    void dilate(io::BlockMaps& maps, uint32_t t0, uint32_t t1, const TexelValues& produce)
    {
        const uint32_t width = grid_.width(), height = grid_.height();
        const int k = k_;
        const io::BlockGrid& local = maps.grid;
        auto at = [&](int j, size_t slot) { return &maps.values[maps.index(uint32_t(j), slot)]; };
        // Per slot: 0 empty, kOwn a texel inside geometry holding its own value (or an empty one filled from
        // such texels), kValid a valid texel's value (or one filled from those).
        constexpr uint8_t kOwn = 1, kValid = 2;
        constexpr uint32_t kAnyChart = ~0u;
        constexpr uint32_t kChunk = 1u << 16;
        std::vector<uint8_t> filled(local.slots(), 0);
        std::vector<uint32_t> slot_chart(chart_ ? local.slots() : 0, kAnyChart);
        values_.resize(size_t(std::min(t1 - t0, kChunk)) * size_t(k));
        for (uint32_t first = t0; first < t1; first += kChunk)
        {
            const uint32_t count = std::min(kChunk, t1 - first);
            produce(first, std::span<glm::vec3>(values_.data(), size_t(count) * size_t(k)));
            for (uint32_t i = first; i < first + count; ++i)
            {
                // Inside geometry: filled from its valid neighbours like an empty texel; where none reaches
                // it (a face no viewer can reach, a chart that lies wholly in a wall) it keeps its own value.
                const glm::uvec2 t = place_(i);
                const size_t slot = size_t(local.slot(t.x, t.y));
                filled[slot] = !valid_.empty() && !valid_[i] ? kOwn : kValid;
                if (chart_)
                    slot_chart[slot] = chart_(i);
                for (int j = 0; j < k; ++j)
                {
                    const glm::vec3& v = values_[size_t(i - first) * size_t(k) + size_t(j)];
                    float* out = at(j, slot);
                    out[0] = v.x;
                    out[1] = v.y;
                    out[2] = v.z;
                }
            }
        }
        std::vector<glm::dvec3> sum(static_cast<size_t>(k));
        for (int pass = 0; pass < dilate_; ++pass)
        {
            // First every texel that valid texels reach (from the values before the pass: those are never
            // rewritten), then the empty ones that only texels holding their own reach (those that kept it).
            std::vector<uint8_t> next = filled;
            for (const uint8_t source : {kValid, kOwn})
                for (size_t slot = 0; slot < local.slots(); ++slot)
                {
                    if (source == kValid ? filled[slot] == kValid : next[slot] != 0)
                        continue;
                    const glm::uvec2 xy = local.texel(slot);
                    if (xy.x >= width || xy.y >= height)
                        continue; // past the atlas in a block of its last column or row
                    int count = 0;
                    std::fill(sum.begin(), sum.end(), glm::dvec3(0.0));
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx)
                        {
                            const int64_t from = local.slot(int64_t(xy.x) + dx, int64_t(xy.y) + dy);
                            if (from < 0 || filled[size_t(from)] != source || next[size_t(from)] != source)
                                continue;
                            // An invalid texel takes only its own chart's light.
                            if (!slot_chart.empty() && filled[slot] == kOwn &&
                                slot_chart[slot] != kAnyChart && slot_chart[size_t(from)] != slot_chart[slot])
                                continue;
                            ++count;
                            for (int j = 0; j < k; ++j)
                            {
                                const float* v = at(j, size_t(from));
                                sum[size_t(j)] += glm::dvec3(v[0], v[1], v[2]);
                            }
                        }
                    if (!count)
                        continue;
                    for (int j = 0; j < k; ++j)
                    {
                        const glm::vec3 v(sum[size_t(j)] / double(count));
                        float* out = at(j, slot);
                        out[0] = v.x;
                        out[1] = v.y;
                        out[2] = v.z;
                    }
                    next[slot] = source;
                }
            filled.swap(next);
        }
    }

    io::BlockGrid grid_;
    uint32_t n_;
    std::function<glm::uvec2(uint32_t)> place_;
    int k_, dilate_;
    std::span<const uint8_t> valid_;
    TexelChart chart_;
    size_t band_slots_;
    uint32_t by_ = 0, halo_ = 0, r0_ = 0;
    std::pair<uint32_t, uint32_t> own_{0, 0};
    std::vector<uint32_t> row_block_, row_texel_;
    std::vector<glm::vec3> values_;
};

// Every band of a BandDilation in turn: emit(maps, first, count, at).
template <typename Place, typename Emit>
void dilate_in_bands(const io::BlockGrid& grid, uint32_t n, const Place& place, int k, int dilate,
                     std::span<const uint8_t> valid, const TexelValues& produce, const TexelChart& chart,
                     size_t band_slots, const Emit& emit)
{
    BandDilation bands(grid, n, place, k, dilate, valid, chart, band_slots);
    BandDilation::Band band;
    while (bands.next(produce, band))
        emit(std::move(band.maps), band.first, band.count, band.at);
}

// The whole atlas dilated at once (dilate_in_bands' one band).
template <typename Place>
io::BlockMaps dilated(uint32_t width, uint32_t height, uint32_t n, const Place& place, int k, int dilate,
                      std::span<const uint8_t> valid, const TexelValues& produce,
                      const TexelChart& chart = {})
{
    io::BlockMaps out;
    dilate_in_bands(dilated_grid(width, height, n, place, dilate), n, place, k, dilate, valid, produce, chart,
                    SIZE_MAX,
                    [&](io::BlockMaps&& maps, uint32_t, uint32_t, uint32_t) { out = std::move(maps); });
    return out;
}
// Each texel's chart, as dilated() takes them, read from the atlas's records.
TexelChart texel_chart(const LightmapAtlas& atlas)
{
    return [&atlas](uint32_t i) { return atlas.texels.chart(i); };
}

io::BlockMaps dilated(const LightmapAtlas& atlas, int k, int dilate, std::span<const uint8_t> valid,
                      const TexelValues& produce)
{
    return dilated(
        atlas.width, atlas.height, uint32_t(atlas.texels.size()),
        [&](uint32_t i) { return atlas.texels.place(i); }, k, dilate, valid, produce, texel_chart(atlas));
}

// A per-texel map over the whole atlas (dilated) read bilinearly at the TEXCOORD_1 of a point of a triangle
// (Embree's barycentrics): what a ray that lands there picks up.
// The UV at Embree's barycentrics (bu, bv) of a triangle whose corners have UVs a, b, c.
glm::vec2 barycentric_uv(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c, float bu, float bv)
{
    return (1.0f - bu - bv) * a + bu * b + bv * c;
}
glm::vec2 atlas_uv(const io::Mesh& mesh, uint32_t triangle, float bu, float bv)
{
    const uint32_t* idx = &mesh.indices[size_t(triangle) * 3];
    return barycentric_uv(mesh.uvs1[idx[0]], mesh.uvs1[idx[1]], mesh.uvs1[idx[2]], bu, bv);
}
glm::vec3 atlas_lookup(const io::Mesh& mesh, const io::BlockMaps& map, uint32_t triangle, float bu, float bv)
{
    return map.bilinear(0, atlas_uv(mesh, triangle, bu, bv));
}

// The previous pass's irradiance over the atlas (dilated), as the bounce rays read it: three half floats a
// texel (6 bytes, half the float map's 12: a bilinear lookup's four texels lie in fewer cache lines, and more
// of the map stays in cache, where the bounce rays land anywhere in the level), the values first scaled by
// the power of two that brings the map's largest value to the top of the halves' range, so that any light
// fits (a 10^5 lux sun, a sky of 10^-4) with the halves' 30 octaves below it. Each channel
// keeps its own value to 2^-11, as the asset's halves do. (A shared exponent, 4 bytes,
// was tried: it keeps a channel only to 2^-10 of the texel's largest, and the bounce of coloured light off
// a saturated surface lost its weaker channels.)
class PackedIrradiance
{
  public:
    struct Taps
    {
        const uint16_t* texel[4]; // as io::BlockMaps::Taps: nullptr where no block is kept
        float tx, ty;
    };

    PackedIrradiance() = default;
    // A map over `grid`'s blocks (dilated_grid's), every value 0 until fill() or broadcast() sets them.
    explicit PackedIrradiance(io::BlockGrid grid) : grid_(std::move(grid)), halves_(grid_.slots() * 3, 0)
    {
        // Each block's rank among the kept ones, for every block of the atlas, where that table takes at most
        // an eighth of the halves (4 bytes a block against 384 a kept block): one load where the grid's rank
        // is a bitmap word and its population count (6% of a bake of the sample level).
        const size_t blocks = size_t(grid_.blocks_x()) * grid_.blocks_y();
        if (blocks <= 12 * grid_.blocks().size())
        {
            rank_.assign(blocks, -1);
            for (size_t b = 0; b < grid_.blocks().size(); ++b)
                rank_[grid_.blocks()[b]] = int32_t(b);
        }
    }
    // The atlas's texels' values (`produce`, one a texel, over the texels of `places`) dilated by `dilate`
    // (dilate_in_bands, in bands of `band_slots`), each band packed into halves as it comes: beyond the
    // halves, one band's floats are held. The scale comes from the largest texel value, valid or not (the
    // dilated values lie between the texels'), read first.
    template <typename Place>
    void fill(uint32_t n, const Place& place, int dilate, std::span<const uint8_t> valid,
              const TexelValues& produce, const TexelChart& chart, size_t band_slots)
    {
        float largest = 0.0f;
        {
            constexpr uint32_t kChunk = 1u << 16;
            std::vector<glm::vec3> values(std::min(n, kChunk));
            for (uint32_t first = 0; first < n; first += kChunk)
            {
                const uint32_t count = std::min(kChunk, n - first);
                produce(first, std::span<glm::vec3>(values.data(), count));
                for (uint32_t i = 0; i < count; ++i)
                    for (int c = 0; c < 3; ++c)
                        largest = std::max(largest, values[i][c]); // NaN is left out
            }
        }
        // The smallest power of two that brings the largest value under the largest half (a dim map up, so
        // that its light stays clear of the halves' subnormals).
        int shift = 0;
        while (std::ldexp(double(kLargest), shift) < double(largest))
            ++shift;
        while (largest > 0.0f && std::ldexp(double(kLargest), shift - 1) >= double(largest))
            --shift;
        scale_ = std::ldexp(1.0f, shift);
        dilate_in_bands(grid_, n, place, 1, dilate, valid, produce, chart, band_slots,
                        [&](io::BlockMaps&& maps, uint32_t first, uint32_t count, uint32_t at)
                        {
                            const size_t to = size_t(first) * io::BlockGrid::kTexels,
                                         from = size_t(at) * io::BlockGrid::kTexels;
                            for (size_t slot = 0; slot < size_t(count) * io::BlockGrid::kTexels; ++slot)
                            {
                                const float* v = &maps.values[maps.index(0, from + slot)];
                                for (size_t c = 0; c < 3; ++c)
                                    halves_[(to + slot) * 3 + c] = to_half(std::ldexp(v[c], -shift));
                            }
                        });
    }
    // The leader's map to every rank (all made over the same grid).
    void broadcast(Distribution& dist)
    {
        dist.broadcast(std::as_writable_bytes(std::span<uint16_t>(halves_)));
        dist.broadcast(std::as_writable_bytes(std::span<float>(&scale_, 1)));
    }

    // The four texels of a bilinear lookup at `uv` (io::bilinear_slots' slots).
    Taps taps(glm::vec2 uv) const
    {
        const io::BilinearSlots b =
            rank_.empty() ? io::bilinear_slots(grid_, uv)
                          : io::bilinear_slots(grid_, uv,
                                               [&](uint32_t block)
                                               {
                                                   const int32_t rank = rank_[block];
                                                   return rank < 0 ? int64_t(-1)
                                                                   : int64_t(rank) * io::BlockGrid::kTexels;
                                               });
        Taps t{{nullptr, nullptr, nullptr, nullptr}, b.tx, b.ty};
        for (int i = 0; i < 4; ++i)
            if (b.slot[i] >= 0)
                t.texel[i] = &halves_[size_t(b.slot[i]) * 3];
        return t;
    }
    glm::vec3 read(const Taps& t) const
    {
        auto at = [&](int i)
        {
            if (!t.texel[i])
                return glm::vec3(0.0f);
            const uint16_t* h = t.texel[i];
            return glm::vec3(from_half(h[0]), from_half(h[1]), from_half(h[2]));
        };
        return io::bilinear_blend(at(0), at(1), at(2), at(3), t.tx, t.ty) * scale_;
    }

  private:
    static constexpr float kLargest = 65504.0f; // the largest finite half
    // A non-negative half's value (glm::unpackHalf1x16's, without its branches): its bits in a float's place
    // (the half's exponent bias is 112 short of a float's) times 2^112, exact for normal and subnormal
    // halves.
    static float from_half(uint16_t h) { return std::bit_cast<float>(uint32_t(h) << 13) * 0x1p112f; }
    // GLM's half of a value (as the asset's), negative and NaN as 0, beyond kLargest as kLargest.
    static uint16_t to_half(float f)
    {
        return uint16_t(glm::packHalf1x16(f > 0.0f ? std::min(f, kLargest) : 0.0f));
    }

    io::BlockGrid grid_;
    std::vector<int32_t> rank_; // per block of the atlas: its rank among the kept ones, or -1 (or empty)
    std::vector<uint16_t> halves_;
    float scale_ = 1.0f;
};

// A texel's samples in one pass, as they come (world direction, and radiance times weight), summed at the
// end by sum(): the SH9 projection of the radiance, and the plain and rnm sums of the radiance times each
// one's clamped cosine, in the texel's tangent frame. In float, kLanes samples at a time into kLanes partial
// sums that are added in a fixed order at the end: a loop the compiler vectorises, with the same bytes on
// any number of threads (and ranks). Against the double sums it replaced, the difference is float's
// rounding over a few hundred samples (about 1e-6 relative), a thousandth of the half floats the asset keeps.
class TexelSamples
{
  public:
    static constexpr size_t kLanes = 8;
    // The sums: 9 SH coefficients, then plain's and rnm's three clamped-cosine sums, each RGB.
    struct Sums
    {
        std::array<glm::vec3, 9> sh;
        std::array<glm::vec3, 4> direct;
    };

    void reserve(size_t n)
    {
        n = (n + kLanes - 1) / kLanes * kLanes;
        if (x_.size() >= n)
            return;
        for (std::vector<float>* v : {&x_, &y_, &z_, &r_, &g_, &b_})
            v->resize(n);
    }
    void clear() { n_ = 0; }
    void push(const glm::vec3& d, const glm::vec3& radiance)
    {
        x_[n_] = d.x;
        y_[n_] = d.y;
        z_[n_] = d.z;
        r_[n_] = radiance.x;
        g_[n_] = radiance.y;
        b_[n_++] = radiance.z;
    }
    Sums sum(const glm::vec3& tangent, const glm::vec3& bitangent, const glm::vec3& normal,
             const std::array<glm::vec3, 3>& rnm, const float (&rnm_scale)[3])
    {
        // The last lanes' samples are zero radiance (their sums add 0).
        const size_t padded = (n_ + kLanes - 1) / kLanes * kLanes;
        for (size_t i = n_; i < padded; ++i)
            x_[i] = y_[i] = z_[i] = r_[i] = g_[i] = b_[i] = 0.0f;
        float acc[13][3][kLanes] = {};
        for (size_t first = 0; first < padded; first += kLanes)
            for (size_t l = 0; l < kLanes; ++l)
            {
                const size_t i = first + l;
                const float wx = x_[i], wy = y_[i], wz = z_[i];
                // glm::dot's order of operations, so that the frame's coordinates are those it gave.
                const float lx = wx * tangent.x + wy * tangent.y + wz * tangent.z;
                const float ly = wx * bitangent.x + wy * bitangent.y + wz * bitangent.z;
                const float lz = wx * normal.x + wy * normal.y + wz * normal.z;
                float w[13];
                math::sh9_basis(lx, ly, lz, w);
                w[9] = std::max(lz, 0.0f);
                for (size_t b = 0; b < 3; ++b)
                    w[10 + b] = std::max(lx * rnm[b].x + ly * rnm[b].y + lz * rnm[b].z, 0.0f) * rnm_scale[b];
                const float c[3] = {r_[i], g_[i], b_[i]};
                for (size_t j = 0; j < 13; ++j)
                    for (size_t ch = 0; ch < 3; ++ch)
                        acc[j][ch][l] += w[j] * c[ch];
            }
        Sums out;
        for (size_t j = 0; j < 13; ++j)
        {
            glm::vec3& v = j < 9 ? out.sh[j] : out.direct[j - 9];
            for (size_t ch = 0; ch < 3; ++ch)
            {
                float total = 0.0f;
                for (size_t l = 0; l < kLanes; ++l)
                    total += acc[j][ch][l];
                v[int(ch)] = total;
            }
        }
        return out;
    }

  private:
    std::vector<float> x_, y_, z_, r_, g_, b_;
    size_t n_ = 0;
};

// A texel's rays, reused from texel to texel by each thread: directions, the rays traced, what they found
// (sized once for the largest stream; a texel uses the first so many of each).
struct RayScratch
{
    void reserve(size_t n)
    {
        if (rays.size() >= n)
            return;
        directions.resize(n);
        rays.resize(n);
        index.resize(n);
        weight.resize(n);
        hits.resize(n);
        blocked.resize(n);
        taps.resize(n);
        for (auto& s : shares)
            s.resize(n);
        stratum.resize(n);
    }

    std::vector<glm::vec3> directions;
    std::vector<Ray> rays;
    std::vector<int> index;     // the sample's index in its stream, per traced ray
    std::vector<double> weight; // the environment rays' weights
    std::vector<std::optional<RayHit>> hits;
    std::vector<uint8_t> blocked;
    std::vector<PackedIrradiance::Taps> taps; // the bounce rays' lookups
    // Per stream of samples (hemisphere, environment, sun) and sample, its share of the denoiser's four
    // guides (LightmapSh::noise).
    std::array<std::vector<std::array<double, 4>>, 3> shares;
    std::vector<float> stratum; // the environment rays' places along the CDF, without their jitter
    TexelSamples samples;
};

// The variance of the sum of a stream's shares (`share[r]`, sample r's part of four values), estimated from
// the stream itself (LightmapSh::noise), added to `variance`: each sample against the mean of its k
// neighbours, sum_r (share_r - mean)^2 / (1 + 1 / k); for independent samples the same with every other as a
// neighbour, count / (count - 1) sum_r (share_r - mean of all)^2. With `stratum` (a pattern that is a ring
// in its first coordinate, cut at a place of the item's own), neighbours more than half the ring away in it
// lie across the cut and are left out (k then the number left).
void add_variance(const std::vector<std::array<double, 4>>& share, const SampleNeighbours& neighbours,
                  std::array<double, 4>& variance, const float* stratum = nullptr)
{
    const size_t count = size_t(neighbours.count);
    if (count < 2)
        return; // one sample says nothing of its spread
    if (neighbours.independent)
    {
        std::array<double, 4> mean{}, sum{};
        for (size_t r = 0; r < count; ++r)
            for (size_t c = 0; c < 4; ++c)
                mean[c] += share[r][c] / double(count);
        for (size_t r = 0; r < count; ++r)
            for (size_t c = 0; c < 4; ++c)
                sum[c] += (share[r][c] - mean[c]) * (share[r][c] - mean[c]);
        for (size_t c = 0; c < 4; ++c)
            variance[c] += sum[c] * double(count) / double(count - 1);
        return;
    }
    const size_t k = size_t(neighbours.k);
    for (size_t r = 0; r < count; ++r)
    {
        std::array<double, 4> mean{};
        size_t used = 0;
        for (size_t q = 0; q < k; ++q)
        {
            const uint32_t j = neighbours.index[r * k + q];
            if (stratum && std::abs(stratum[r] - stratum[j]) > 0.5f)
                continue;
            for (size_t c = 0; c < 4; ++c)
                mean[c] += share[j][c];
            ++used;
        }
        for (size_t c = 0; c < 4 && used; ++c)
        {
            const double d = share[r][c] - mean[c] / double(used);
            variance[c] += d * d / (1.0 + 1.0 / double(used));
        }
    }
}

} // namespace

bool light_reaches(const io::PunctualLight& p, const glm::vec3& x)
{
    if (p.type == io::PunctualLight::Type::Directional || !(p.range > 0.0f))
        return true;
    const glm::vec3 d = x - p.position;
    return glm::dot(d, d) < p.range * p.range;
}

std::vector<ShadowmaskChannel> shadowmask_channels(const LightmapLights& lights)
{
    // The mixed lights in order, each with its reach: a sphere (centre, radius), radius INFINITY for
    // everywhere.
    struct Mixed
    {
        int light;
        glm::vec3 centre;
        float radius;
        std::string name;
    };
    std::vector<Mixed> mixed;
    if (lights.sun && lights.sun_mode == io::LightMode::Mixed)
        mixed.push_back({-1, glm::vec3(0.0f), INFINITY, "the sun (--sun)"});
    for (size_t i = 0; i < lights.punctual.size(); ++i)
    {
        const io::PunctualLight& p = lights.punctual[i];
        if (p.mode != io::LightMode::Mixed)
            continue;
        const bool everywhere = p.type == io::PunctualLight::Type::Directional || !(p.range > 0.0f);
        mixed.push_back({int(i), p.position, everywhere ? INFINITY : p.range,
                         "light " + std::to_string(i) + (p.name.empty() ? "" : " '" + p.name + "'")});
    }
    std::vector<ShadowmaskChannel> out;
    for (size_t a = 0; a < mixed.size(); ++a)
    {
        bool taken[4] = {};
        std::string holders;
        for (size_t b = 0; b < a; ++b)
        {
            const float reach = mixed[a].radius + mixed[b].radius;
            if (std::isfinite(reach) && glm::length(mixed[a].centre - mixed[b].centre) >= reach)
                continue;
            taken[out[b].channel] = true;
            holders += (holders.empty() ? "" : ", ") + mixed[b].name;
        }
        int channel = 0;
        while (channel < 4 && taken[channel])
            ++channel;
        if (channel == 4)
            throw std::invalid_argument(
                "mixed " + mixed[a].name + " reaches where the shadowmask's four channels are held by " +
                holders +
                ": a texel keeps the shadows of at most four mixed lights; make it baked or realtime "
                "(extras.hemi_bake_mode), or give it a range that does not reach the others");
        out.push_back({mixed[a].light, channel});
    }
    return out;
}

LightmapSh bake_lightmap_sh(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapLights& lights,
                            const LightmapBakeOptions& o, const LightmapSurfaces* surfaces,
                            const std::function<void(const LightmapProgress&)>& progress)
{
    check(lights, o);
    if (o.bounces > 0 && !surfaces)
        throw std::invalid_argument("bounces need the scene's surfaces (their albedo)");
    if (o.bounces > 0 && mesh.uvs1.size() != mesh.positions.size())
        throw std::invalid_argument("bounces need lightmap UVs to look the irradiance of a hit up");
    LightmapSh out;
    out.width = atlas.width;
    out.height = atlas.height;
    const uint32_t n = uint32_t(atlas.texels.size());
    if (n == 0)
        return out;
    const EmbreeScene scene(mesh);
    const float offset = scene.ray_offset(o.ray_offset);
    const double weight = 2.0 * M_PI / double(o.rays);
    const int passes = 1 + o.bounces;
    // An image environment is importance-sampled by its own rays (the hemisphere rays then gather only what
    // surfaces send); a uniform one is gathered by the hemisphere rays.
    const detail::LightSampler light(lights, o.seed);
    const bool image_env = light.image_environment();

    // The finished work: the SH of the completed passes, the pass being gathered, and the irradiance at each
    // texel's normal that the previous pass left (what a bounce ray picks up where it lands).
    // Who computes the texels (shared among the ranks of a job like a pass, once they agree on what they
    // bake), and in tiles of how many: every rank runs the leader's tiles.
    Distribution& dist = o.distribution ? *o.distribution : local_distribution();
    uint32_t tile_texels = o.tile_texels;
    dist.broadcast(std::as_writable_bytes(std::span<uint32_t>(&tile_texels, 1)));
    const bool tiled = tile_texels > 0 && tile_texels < n;
    if (tiled && o.tile_file.empty())
        throw std::invalid_argument("a lightmap bake in tiles needs a file for them (tile_file)");
    // A pass's texels are computed into pass_* (a tile of them, or all), and added to the sums of the passes
    // before: out's arrays, or with tiles the tile file's, a tile at a time through sum_*.
    const uint32_t tile = tiled ? tile_texels : n;
    using ShArray = std::array<glm::vec3, 9>;
    using DirectArray = std::array<glm::vec3, 4>;
    std::vector<ShArray> pass_sh(tile);
    std::vector<DirectArray> pass_direct(tile);
    std::vector<LightmapSh::Noise> pass_noise(o.keep_noise ? tile : 0);
    std::vector<ShArray> sum_sh(tiled ? tile : 0);
    std::vector<DirectArray> sum_direct(tiled ? tile : 0);
    std::vector<LightmapSh::Noise> sum_noise(tiled && o.keep_noise ? tile : 0);
    std::vector<glm::vec3> tile_bounce(tiled ? tile : 0);
    out.irradiance.assign(tiled ? 0 : n, {});
    out.direct.assign(tiled ? 0 : n, {});
    out.noise.assign(o.keep_noise && !tiled ? n : 0, {});
    // rnm's directions in the tangent frame and the factor that makes each give pi under uniform radiance 1
    // over the hemisphere (lightmap_bake.h).
    const std::array<glm::vec3, 3>& rnm = math::rnm_basis();
    float rnm_scale[3];
    for (size_t b = 0; b < 3; ++b)
        rnm_scale[b] = float(2.0 / (1.0 + double(rnm[b].z)));
    // The irradiance at each texel's normal that the pass before left (what the bounce map is made from):
    // without tiles here; with tiles in the tile file beside the sums (kBounceField), the pass's own copy.
    std::vector<glm::vec3> previous(tiled ? 0 : n, glm::vec3(0.0f));
    out.valid.assign(n, 1);
    // The mixed lights' channels; their shadowmask and direct light (28 bytes a texel) are kept for every
    // texel, or with tiles for a tile's (indexed from its first texel, like pass_*), every tile's in the tile
    // file (copy 0, written in the first pass).
    const std::vector<ShadowmaskChannel> channels = shadowmask_channels(lights);
    int sun_channel = -1;
    std::vector<int> punctual_channel(lights.punctual.size(), -1);
    for (const ShadowmaskChannel& c : channels)
        (c.light < 0 ? sun_channel : punctual_channel[size_t(c.light)]) = c.channel;
    const bool mixed = !channels.empty();
    out.shadowmask.assign(mixed && !tiled ? n : 0, {1.0f, 1.0f, 1.0f, 1.0f});
    out.mixed_direct.assign(mixed && !tiled ? n : 0, glm::vec3(0.0f));
    std::vector<std::array<float, 4>> tile_mask(mixed && tiled ? tile : 0);
    std::vector<glm::vec3> tile_mixed(mixed && tiled ? tile : 0);
    std::array<float, 4>* const mask_out = tiled ? tile_mask.data() : out.shadowmask.data();
    glm::vec3* const mixed_out = tiled ? tile_mixed.data() : out.mixed_direct.data();
    const bool sun_lit = lights.sun && lights.sun_mode != io::LightMode::Realtime;
    PackedIrradiance previous_map; // `previous` over the atlas, dilated, for bilinear lookups
    tbb::enumerable_thread_specific<RayScratch> scratch;

    // Against light leaking, each texel's rays start where detail::TexelOrigins puts them: moved out of a
    // wall its footprint reaches behind, or to the part of its footprint outside geometry; a texel inside
    // geometry wherever its footprint was tried is invalid (its value comes from its valid neighbours, by
    // the dilation, in the outputs and for the bounces).
    const detail::TexelOrigins texel_origins(scene, mesh, atlas.width, atlas.height, offset,
                                             [&](uint32_t t)
                                             { return surfaces && surfaces->double_sided(t); });
    // What a hemisphere ray needs of the triangle it hits, in one record of 40 bytes (one cache line, where
    // the mesh's indices, lightmap UVs, Embree's normals and the materials are four: a level of a million
    // triangles does not stay in cache): its lightmap UVs, and whether the ray meets its back (as
    // TexelOrigins::back_face says, from the same normal and material).
    struct HitTriangle
    {
        glm::vec2 uv[3];
        glm::vec3 normal;
        uint32_t double_sided;
    };
    std::vector<HitTriangle> hit_triangles(mesh.indices.size() / 3);
    const bool uvs = mesh.uvs1.size() == mesh.positions.size();
    tbb::parallel_for(size_t(0), hit_triangles.size(),
                      [&](size_t t)
                      {
                          HitTriangle& h = hit_triangles[t];
                          for (size_t c = 0; c < 3; ++c)
                              h.uv[c] = uvs ? mesh.uvs1[mesh.indices[t * 3 + c]] : glm::vec2(0.0f);
                          h.normal = scene.geometric_normal(uint32_t(t));
                          h.double_sided = surfaces && surfaces->double_sided(uint32_t(t));
                      });
    auto is_back_face = [&](uint32_t primitive, const glm::vec3& d)
    {
        const HitTriangle& h = hit_triangles[primitive];
        return glm::dot(h.normal, d) > 0.0f && !h.double_sided;
    };
    // Shared among the ranks like a pass (each texel's origin depends on the scene alone).
    const uint64_t key = key_of(mesh, atlas, lights, o, surfaces,
                                surfaces ? std::span<const io::Material>(surfaces->materials())
                                         : std::span<const io::Material>(),
                                tiled);
    dist.check_same(key, "baked a lightmap whose scene, atlas, lights or options");
    // What the checkpoint saves: without tiles, the sums and the pass so far; with tiles, the irradiance at
    // the normals of the pass before and of this one so far (the sums are in the tile file, synced before the
    // checkpoint counts a tile as done).
    std::vector<CheckpointSection> sections;
    if (!tiled)
        sections = {{"irradiance", std::as_writable_bytes(std::span<ShArray>(out.irradiance))},
                    {"pass", std::as_writable_bytes(std::span<ShArray>(pass_sh))},
                    {"direct", std::as_writable_bytes(std::span<DirectArray>(out.direct))},
                    {"pass_direct", std::as_writable_bytes(std::span<DirectArray>(pass_direct))},
                    {"noise", std::as_writable_bytes(std::span<LightmapSh::Noise>(out.noise))},
                    {"pass_noise", std::as_writable_bytes(std::span<LightmapSh::Noise>(pass_noise))},
                    {"previous", std::as_writable_bytes(std::span<glm::vec3>(previous))},
                    {"valid", std::as_writable_bytes(std::span<uint8_t>(out.valid))}};
    else
        sections = {{"valid", std::as_writable_bytes(std::span<uint8_t>(out.valid))}};
    sections.push_back(
        {"shadowmask", std::as_writable_bytes(std::span<std::array<float, 4>>(out.shadowmask))});
    sections.push_back({"mixed_direct", std::as_writable_bytes(std::span<glm::vec3>(out.mixed_direct))});
    SliceCheckpoint checkpoint(dist.leader() ? o.checkpoint : std::filesystem::path(), key, uint32_t(passes),
                               n, std::move(sections), o.checkpoint_seconds);
    SlicePosition state;
    if (const std::optional<SlicePosition> resumed = checkpoint.resume(dist)) // every rank from the leader's
    {
        state = *resumed;
        out.resumed = true;
    }
    // The tile file: on the leader, which alone keeps the sums. Kept while a checkpoint may need it.
    std::shared_ptr<TexelFile> tiles;
    if (tiled && dist.leader())
    {
        std::vector<uint32_t> fields = {uint32_t(sizeof(ShArray)), uint32_t(sizeof(DirectArray)),
                                        uint32_t(sizeof(glm::vec3)), uint32_t(sizeof(glm::vec3)), 1};
        if (o.keep_noise)
            fields.push_back(uint32_t(sizeof(LightmapSh::Noise)));
        if (mixed)
        {
            out.tiles_mixed_field = int(fields.size());
            fields.push_back(uint32_t(sizeof(std::array<float, 4>)));
            fields.push_back(uint32_t(sizeof(glm::vec3)));
        }
        tiles = std::make_shared<TexelFile>(o.tile_file, key, n, std::move(fields), out.resumed);
        if (checkpoint.active())
            tiles->keep();
    }
    // Each texel's ray origin and whether it was moved out of a wall: without tiles here for every texel;
    // with tiles here for a tile's (origins[i - base]), every tile's in the tile file (kOriginField,
    // kMovedField, copy 0), read back and sent to every rank before the tile's work (load_origins).
    std::vector<glm::vec3> origins(tile);
    std::vector<uint8_t> pushed(tile, 0);
    uint32_t base = 0; // the first texel of the tile being worked on: origins[0], pass_*[0]
    const auto load_origins = [&](uint32_t begin, uint32_t count)
    {
        base = tiled ? begin : 0;
        if (!tiled)
            return;
        if (tiles)
        {
            tiles->read(0, kOriginField, begin, std::as_writable_bytes(std::span(origins.data(), count)));
            tiles->read(0, kMovedField, begin, std::as_writable_bytes(std::span(pushed.data(), count)));
        }
        dist.broadcast(std::as_writable_bytes(std::span(origins.data(), count)));
        dist.broadcast(std::as_writable_bytes(std::span(pushed.data(), count)));
    };
    auto find_origin = [&](uint32_t i)
    {
        const LightmapTexel& t = atlas.texels[i];
        const detail::TexelOrigins::Origin found =
            texel_origins.find(t.triangle, t.x, t.y, t.barycentric, &t.tangent);
        origins[i - base] = found.origin;
        pushed[i - base] = found.moved;
        out.valid[i] = !found.inside;
    };
    for (uint32_t begin = 0; begin < n; begin += tile)
    {
        const uint32_t end = std::min(n, begin + tile);
        base = begin;
        const ItemArray origin_arrays[3] = {{reinterpret_cast<std::byte*>(origins.data()), sizeof(glm::vec3)},
                                            {reinterpret_cast<std::byte*>(pushed.data()), 1},
                                            {reinterpret_cast<std::byte*>(out.valid.data() + base), 1}};
        dist.run(
            0, end - begin, std::min<uint32_t>(uint32_t(1) << 18, end - begin), origin_arrays,
            [&](uint32_t b, uint32_t e)
            {
                tbb::parallel_for(tbb::blocked_range<uint32_t>(base + b, base + e, 64),
                                  [&](const tbb::blocked_range<uint32_t>& r)
                                  {
                                      for (uint32_t i = r.begin(); i != r.end(); ++i)
                                          find_origin(i);
                                  });
            },
            [](uint32_t) {});
        for (uint32_t i = 0; i < end - begin; ++i)
            out.pushed += pushed[i];
        if (tiles)
        {
            tiles->write(0, kOriginField, begin, std::as_bytes(std::span(origins.data(), end - begin)));
            tiles->write(0, kMovedField, begin, std::as_bytes(std::span(pushed.data(), end - begin)));
        }
    }
    // A texel inside geometry that texels outside it see is outside all the same (TexelOrigins::seen): its
    // rays start from its centre's origin, and those that meet the backs of walls bring no light. (Each
    // texel's answer reads the others' validity as the origins left it: it is kept apart until all are in.)
    std::vector<uint8_t> seen(n, 0);
    for (uint32_t begin = 0; begin < n; begin += tile)
    {
        const uint32_t end = std::min(n, begin + tile);
        load_origins(begin, end - begin);
        const ItemArray seen_array[1] = {{reinterpret_cast<std::byte*>(seen.data() + base), 1}};
        dist.run(
            0, end - begin, std::min<uint32_t>(uint32_t(1) << 18, end - begin), seen_array,
            [&](uint32_t b, uint32_t e)
            {
                tbb::parallel_for(
                    tbb::blocked_range<uint32_t>(base + b, base + e, 64),
                    [&](const tbb::blocked_range<uint32_t>& r)
                    {
                        for (uint32_t i = r.begin(); i != r.end(); ++i)
                        {
                            if (out.valid[i])
                                continue;
                            const LightmapTexel& t = atlas.texels[i];
                            // A point on a texel inside geometry (its own triangle's) is inside geometry.
                            auto may_be_outside = [&](const RayHit& hit)
                            {
                                const glm::vec2 uv = atlas_uv(mesh, hit.primitive, hit.u, hit.v);
                                const int32_t at =
                                    atlas.texel_of(int64_t(std::floor(uv.x * float(atlas.width))),
                                                   int64_t(std::floor(uv.y * float(atlas.height))));
                                return at < 0 || out.valid[size_t(at)] ||
                                       atlas.texels.triangle(size_t(at)) != hit.primitive;
                            };
                            seen[i] = texel_origins.seen(origins[i - base], t.triangle,
                                                         uint64_t(t.y) * atlas.width + t.x, may_be_outside);
                        }
                    });
            },
            [](uint32_t) {});
    }
    for (uint32_t i = 0; i < n; ++i)
        out.valid[i] |= seen[i];
    std::vector<uint8_t>().swap(seen);

    // The noise estimate's patterns (LightmapSh::noise): each sample is compared with its six nearest in its
    // stream's. The sun's rays are drawn independently.
    const SampleNeighbours hemisphere_pattern =
                               o.keep_noise ? hemisphere_neighbours(o.rays, 6) : SampleNeighbours{},
                           environment_pattern =
                               o.keep_noise && image_env ? lattice_neighbours(o.rays, 6) : SampleNeighbours{};
    SampleNeighbours sun_pattern;
    sun_pattern.count = o.sun_rays;
    sun_pattern.independent = true;
    // Band 1's factor in the cosine's convolution (a guide's share is the luminance times it).
    const double band1 = []
    {
        math::Sh9Rgb unit{};
        unit[1] = glm::vec3(1.0f);
        return double(math::convolve_cosine(unit)[1].x);
    }();
    auto texel = [&](uint32_t i, int pass)
    {
        const LightmapTexel& t = atlas.texels[i];
        const uint64_t item = uint64_t(t.y) * atlas.width + t.x;
        const glm::vec3 origin = origins[i - base];
        RayScratch& s = scratch.local();
        s.reserve(size_t(std::max(o.rays, o.sun_rays)));
        s.samples.reserve(size_t(2 * o.rays + o.sun_rays) + lights.punctual.size());
        s.samples.clear();
        if (o.keep_noise)
            for (size_t stream = 0; stream < 3; ++stream)
                std::fill_n(s.shares[stream].begin(), stream == 2 ? o.sun_rays : o.rays,
                            std::array<double, 4>{});
        // `stream`: 0 the hemisphere rays, 1 the environment's, 2 the sun's, -1 an exact sample (a punctual
        // light); `ray`: the sample's index in its stream.
        // A sample of radiance (times its weight) from `world`; summed with the others at the end.
        auto add = [&](const glm::vec3& world, const glm::dvec3& radiance, int stream, int ray)
        {
            if (o.keep_noise && stream >= 0)
            {
                // Its share of the guides: luminance times the clamped cosine, and times band 1's
                // functions as the cosine's convolution scales them.
                const glm::vec3 local(glm::dot(world, t.tangent), glm::dot(world, t.bitangent),
                                      glm::dot(world, t.normal));
                const math::Sh9 y = math::sh9_eval(local);
                const double l = double(math::luminance(glm::vec3(radiance)));
                std::array<double, 4>& share = s.shares[size_t(stream)][size_t(ray)];
                share[0] += l * double(std::max(local.z, 0.0f));
                for (size_t b = 0; b < 3; ++b)
                    share[1 + b] += l * double(y[1 + b]) * band1;
            }
            s.samples.push(world, glm::vec3(radiance));
        };
        // Each pass draws its own directions (seed per pass), so the passes' noise does not line up. The
        // texel's rays are traced together (EmbreeScene's packets), then their hits are shaded in ray order.
        const uint64_t seed = pass == 0 ? o.seed : mix64(o.seed + uint64_t(pass) * 0x9E3779B97F4A7C15ull);
        // The hemisphere rays gather a uniform environment and emission in the first pass, what the pass
        // before left on the surfaces after it.
        const bool needs_hit = pass == 0 ? !image_env || surfaces : surfaces != nullptr;
        size_t m = 0; // the rays traced
        if (needs_hit)
        {
            const std::span<glm::vec3> directions(s.directions.data(), size_t(o.rays));
            hemisphere_directions(seed, item, directions);
            for (int r = 0; r < o.rays; ++r)
            {
                const glm::vec3& h = directions[size_t(r)];
                const glm::vec3 d = glm::normalize(h.x * t.tangent + h.y * t.bitangent + h.z * t.normal);
                if (glm::dot(d, t.geometric_normal) <= 0.0f)
                    continue; // into its own triangle
                s.rays[m] = {origin, 0.0f, d, INFINITY};
                s.index[m++] = r;
            }
        }
        scene.intersect(std::span<const Ray>(s.rays.data(), m), std::span(s.hits.data(), m));
        // Light leaves a surface from its front (counter-clockwise) side, or both of a double-sided one.
        // A bounce ray's lookup of the previous pass: every lookup's texels are fetched before any is read.
        const bool lookups = surfaces && pass > 0;
        // s.blocked: here 1 for a ray that hit a back face.
        for (size_t k = 0; k < m; ++k)
        {
            const std::optional<RayHit>& hit = s.hits[k];
            s.blocked[k] = hit && is_back_face(hit->primitive, s.rays[k].direction);
            if (!lookups || !hit || s.blocked[k])
                continue;
            const HitTriangle& h = hit_triangles[hit->primitive];
            s.taps[k] = previous_map.taps(barycentric_uv(h.uv[0], h.uv[1], h.uv[2], hit->u, hit->v));
            for (const uint16_t* p : s.taps[k].texel)
                if (p)
                    __builtin_prefetch(p);
        }
        for (size_t k = 0; k < m; ++k)
        {
            const glm::vec3& d = s.rays[k].direction;
            const std::optional<RayHit>& hit = s.hits[k];
            const int r = s.index[k];
            if (!hit)
            {
                if (pass == 0 && !image_env)
                    add(d, glm::dvec3(lights.environment_radiance(d)) * weight, 0, r);
                continue;
            }
            if (s.blocked[k])
                continue;
            if (!surfaces)
                continue;
            glm::vec3 radiance = pass == 0 ? surfaces->emission(hit->primitive, hit->u, hit->v)
                                           : surfaces->albedo(hit->primitive, hit->u, hit->v) *
                                                 previous_map.read(s.taps[k]) / float(M_PI);
            if (radiance != glm::vec3(0.0f))
                add(d, glm::dvec3(radiance) * weight, 0, r);
        }
        // Shadow rays, traced together and then taken in order: `count` rays of a stream, ray(r, d, w)
        // saying whether ray r is cast (its direction and weight), visible(d, w, r) called for each that
        // reaches the light.
        auto shadow_rays = [&](int count, auto&& ray, auto&& visible)
        {
            size_t cast = 0;
            for (int r = 0; r < count; ++r)
            {
                glm::vec3 d;
                double w = 0.0;
                if (!ray(r, d, w))
                    continue;
                s.rays[cast] = {origin, 0.0f, d, INFINITY};
                s.index[cast] = r;
                s.weight[cast++] = w;
            }
            scene.occluded(std::span<const Ray>(s.rays.data(), cast), std::span(s.blocked.data(), cast));
            for (size_t k = 0; k < cast; ++k)
                if (!s.blocked[k])
                    visible(s.rays[k].direction, s.weight[k], s.index[k]);
        };
        // The mixed lights' shadowmask channels and direct irradiance at the normal.
        std::array<float, 4> mask = {1.0f, 1.0f, 1.0f, 1.0f};
        glm::dvec3 mixed_e(0.0);
        if (pass == 0 && image_env)
            shadow_rays(
                o.rays,
                [&](int r, glm::vec3& d, double& w)
                {
                    // Below the surface: the hemisphere of the frame, as the uniform rays see it.
                    return light.environment_ray(item, r, o.rays, d, w) &&
                           glm::dot(d, t.geometric_normal) > 0.0f && glm::dot(d, t.normal) > 0.0f;
                },
                [&](const glm::vec3& d, double w, int r)
                { add(d, glm::dvec3(lights.environment_radiance(d)) * w, 1, r); });
        if (sun_lit && pass == 0)
        {
            // A directional light of irradiance E projects to E y(d): its delta radiance, per sample. A mixed
            // sun's samples go to its shadowmask channel (the share that reaches the texel; rays below the
            // surface do not) and to the bounces' light, not to the lightmap.
            const glm::dvec3 e = glm::dvec3(lights.sun_irradiance) / double(o.sun_rays);
            int visible = 0;
            shadow_rays(
                o.sun_rays,
                [&](int r, glm::vec3& d, double&)
                {
                    d = light.sun_ray(item, r);
                    return glm::dot(d, t.geometric_normal) > 0.0f;
                },
                [&](const glm::vec3& d, double, int r)
                {
                    if (sun_channel < 0)
                        return add(d, e, 2, r);
                    ++visible;
                    mixed_e += e * double(std::max(glm::dot(d, t.normal), 0.0f));
                });
            if (sun_channel >= 0)
                mask[size_t(sun_channel)] *= float(visible) / float(o.sun_rays);
        }
        if (pass == 0)
            for (size_t l = 0; l < lights.punctual.size(); ++l)
            {
                const io::PunctualLight& p = lights.punctual[l];
                if (p.mode == io::LightMode::Realtime)
                    continue;
                glm::vec3 d(0.0f, 0.0f, 1.0f);
                float distance = INFINITY;
                // A texel moved out of a wall is lit where its rays start.
                const glm::vec3 at = pushed[i - base] ? origin : t.position;
                const glm::vec3 e = light.punctual(p, at, d, distance);
                if (const int c = punctual_channel[l]; c >= 0)
                {
                    // A mixed light's visibility, wherever it reaches (its channel is 1 where none of the
                    // channel's lights does), lit or not by its cone: the run time's light is multiplied by
                    // it.
                    if (!light_reaches(p, at))
                        continue;
                    const bool reached =
                        distance > 0.0f && glm::dot(d, t.geometric_normal) > 0.0f &&
                        !scene.occluded(origin, d, 0.0f,
                                        std::isfinite(distance) ? distance * (1.0f - 1e-4f) : INFINITY);
                    mask[size_t(c)] *= reached ? 1.0f : 0.0f;
                    if (reached)
                        mixed_e += glm::dvec3(e) * double(std::max(glm::dot(d, t.normal), 0.0f));
                    continue;
                }
                if (e == glm::vec3(0.0f) || glm::dot(d, t.geometric_normal) <= 0.0f)
                    continue;
                // The shadow ray stops short of the light (it must not hit geometry behind it).
                if (scene.occluded(origin, d, 0.0f,
                                   std::isfinite(distance) ? distance * (1.0f - 1e-4f) : INFINITY))
                    continue;
                add(d, glm::dvec3(e), -1, 0);
            }
        const TexelSamples::Sums sums = s.samples.sum(t.tangent, t.bitangent, t.normal, rnm, rnm_scale);
        pass_sh[i - base] = math::convolve_cosine(sums.sh);
        pass_direct[i - base] = sums.direct;
        if (mixed && pass == 0)
        {
            mask_out[i - base] = mask;
            mixed_out[i - base] = glm::vec3(mixed_e);
        }
        if (o.keep_noise)
        {
            std::array<double, 4> variance{};
            add_variance(s.shares[0], hemisphere_pattern, variance);
            if (pass == 0 && image_env)
            {
                const double start = light.environment_offset(item, o.rays);
                for (int r = 0; r < o.rays; ++r)
                {
                    const double x = double(r) / double(o.rays) + start;
                    s.stratum[size_t(r)] = float(x - std::floor(x));
                }
                add_variance(s.shares[1], environment_pattern, variance, s.stratum.data());
            }
            if (pass == 0 && sun_lit)
                add_variance(s.shares[2], sun_pattern, variance);
            for (size_t c = 0; c < 4; ++c)
                pass_noise[i - base][c] = float(variance[c]);
        }
    };

    const uint64_t rays_per_texel =
        uint64_t(o.rays) * (image_env ? 2 : 1) + (sun_lit ? uint64_t(o.sun_rays) : 0) +
        uint64_t(std::count_if(lights.punctual.begin(), lights.punctual.end(),
                               [](const io::PunctualLight& p) { return p.mode != io::LightMode::Realtime; }));
    // At least 256 texels a slice, at most a tile (std::clamp would be undefined for a tile under 256).
    const uint32_t slice =
        uint32_t(std::min<uint64_t>(std::max<uint64_t>((uint64_t(1) << 21) / rays_per_texel, 256), tile));
    // With tiles, a checkpoint that could not be saved must not stay behind: the next pass overwrites the
    // copy of the tile file that a resume from the last good one would read. So it goes, and the tiles with
    // it.
    const auto forget_failed_checkpoint = [&]
    {
        if (!tiles || checkpoint.active() || o.checkpoint.empty())
            return;
        remove_checkpoint(o.checkpoint);
        tiles->keep(false);
    };
    const auto t0 = std::chrono::steady_clock::now();
    for (int pass = int(state.pass); pass < passes; ++pass)
    {
        const uint32_t first = pass == int(state.pass) ? state.next_item : 0;
        if (first == n)
            continue; // resumed after this pass was added in
        if (pass > 0)
        {
            // The bounce map, from the pass before: without tiles on every rank from `previous`, with tiles
            // on the leader from the tile file and then sent to the others.
            const auto place = [&](uint32_t i) { return atlas.texels.place(i); };
            previous_map =
                PackedIrradiance(dilated_grid(atlas.width, atlas.height, n, place, kBounceDilation));
            const TexelValues produce = [&](uint32_t from, std::span<glm::vec3> values)
            {
                if (tiled)
                    tiles->read((pass - 1) % 2, kBounceField, from, std::as_writable_bytes(values));
                else
                    std::copy_n(previous.begin() + from, values.size(), values.begin());
            };
            if (!tiled || tiles)
                previous_map.fill(
                    n, place, kBounceDilation, out.valid, produce, texel_chart(atlas),
                    std::min<size_t>(kBounceBandSlots, std::max<size_t>(tile, kBounceBandLeastSlots)));
            if (tiled)
                previous_map.broadcast(dist);
        }
        if (progress && dist.leader())
            progress({pass, passes, first, n, checkpoint.error()});
        // Without tiles, one run over the whole pass; with tiles, one per tile, each added to the tile file
        // before the next.
        for (uint32_t begin = first; begin < n; begin = tiled ? std::min(n, begin + tile) : n)
        {
            const uint32_t end = tiled ? std::min(n, begin + tile) : n;
            load_origins(begin, end - begin);
            // What a texel's work writes, which every rank gathers.
            std::vector<ItemArray> arrays = {
                {reinterpret_cast<std::byte*>(pass_sh.data()), sizeof(ShArray)},
                {reinterpret_cast<std::byte*>(pass_direct.data()), sizeof(DirectArray)}};
            if (o.keep_noise)
                arrays.push_back(
                    {reinterpret_cast<std::byte*>(pass_noise.data()), sizeof(LightmapSh::Noise)});
            if (mixed && pass == 0) // indexed from the tile's first texel, like the pass's
            {
                arrays.push_back({reinterpret_cast<std::byte*>(mask_out), sizeof(std::array<float, 4>)});
                arrays.push_back({reinterpret_cast<std::byte*>(mixed_out), sizeof(glm::vec3)});
            }
            dist.run(
                begin - base, end - base, tiled ? std::min(slice, end - begin) : slice, arrays,
                [&](uint32_t b, uint32_t e)
                {
                    tbb::parallel_for(tbb::blocked_range<uint32_t>(base + b, base + e, 64),
                                      [&](const tbb::blocked_range<uint32_t>& r)
                                      {
                                          for (uint32_t i = r.begin(); i != r.end(); ++i)
                                              texel(i, pass);
                                      });
                },
                [&](uint32_t next)
                {
                    if (!tiled)
                        checkpoint.slice_done(uint32_t(pass), next);
                    if (progress)
                        progress({pass, passes, base + next, n, checkpoint.error()});
                });
            if (!tiled)
                continue;
            // The tile is complete: its sums of the passes before (copy (pass - 1) % 2) plus this pass, to
            // copy pass % 2 (texel_file.h: a tile written twice gives the same bytes).
            const uint32_t count = end - begin;
            if (tiles)
            {
                auto io_tile = [&](bool write, int copy, size_t field, auto& v)
                {
                    const auto bytes = std::as_writable_bytes(std::span(v.data(), count));
                    if (write)
                        tiles->write(copy, field, begin, bytes);
                    else
                        tiles->read(copy, field, begin, bytes);
                };
                if (pass > 0)
                {
                    io_tile(false, (pass - 1) % 2, 0, sum_sh);
                    io_tile(false, (pass - 1) % 2, 1, sum_direct);
                    if (o.keep_noise)
                        io_tile(false, (pass - 1) % 2, kNoiseField, sum_noise);
                }
                else
                {
                    std::fill_n(sum_sh.begin(), count, ShArray{});
                    std::fill_n(sum_direct.begin(), count, DirectArray{});
                    if (o.keep_noise)
                        std::fill_n(sum_noise.begin(), count, LightmapSh::Noise{});
                }
                for (uint32_t i = 0; i < count; ++i)
                {
                    for (int j = 0; j < 9; ++j)
                        sum_sh[i][size_t(j)] += pass_sh[i][size_t(j)];
                    for (size_t b = 0; b < 4; ++b)
                        sum_direct[i][b] += pass_direct[i][b];
                    if (o.keep_noise)
                        for (size_t c = 0; c < 4; ++c)
                            sum_noise[i][c] += pass_noise[i][c];
                }
                io_tile(true, pass % 2, 0, sum_sh);
                io_tile(true, pass % 2, 1, sum_direct);
                if (o.keep_noise)
                    io_tile(true, pass % 2, kNoiseField, sum_noise);
                // The bounces start from all of the first pass's light, the mixed lights' direct light too.
                for (uint32_t i = 0; i < count; ++i)
                    tile_bounce[i] =
                        pass_direct[i][0] + (mixed && pass == 0 ? tile_mixed[i] : glm::vec3(0.0f));
                io_tile(true, pass % 2, kBounceField, tile_bounce);
                if (mixed && pass == 0)
                {
                    io_tile(true, 0, size_t(out.tiles_mixed_field), tile_mask);
                    io_tile(true, 0, size_t(out.tiles_mixed_field) + 1, tile_mixed);
                }
                if (checkpoint.active())
                    tiles->sync();
            }
            if (end < n)
                checkpoint.slice_done(uint32_t(pass), end);
            forget_failed_checkpoint();
            if (progress && dist.leader())
                progress({pass, passes, end, n, checkpoint.error()});
        }
        out.rays += uint64_t(n - first) * (pass == 0 ? rays_per_texel : uint64_t(o.rays));
        // The pass is complete: add it (without tiles), and keep its irradiance at each normal for the next
        // bounce.
        if (!tiled)
            for (uint32_t i = 0; i < n; ++i)
            {
                for (int j = 0; j < 9; ++j)
                    out.irradiance[i][size_t(j)] += pass_sh[i][size_t(j)];
                for (size_t b = 0; b < 4; ++b)
                    out.direct[i][b] += pass_direct[i][b];
                if (o.keep_noise)
                    for (size_t c = 0; c < 4; ++c)
                        out.noise[i][c] += pass_noise[i][c];
                previous[i] = pass_direct[i][0]; // E at the normal, integrated directly
                if (mixed && pass == 0)
                    previous[i] += out.mixed_direct[i]; // the bounces carry the mixed lights' light
            }
        // With tiles, a save at the end of every pass: the next pass overwrites the copy of the tile file
        // that a resume from a save in this pass would read (texel_file.h).
        checkpoint.slice_done(uint32_t(pass), n, tiled);
        forget_failed_checkpoint();
        if (progress && dist.leader())
            progress({pass, passes, n, n, checkpoint.error()});
    }
    if (tiles)
    {
        out.tiles = tiles;
        out.tiles_copy = (passes - 1) % 2;
        out.tiles_noise = o.keep_noise;
    }
    out.tiles_count = tiled ? (n + tile - 1) / tile : 1;
    out.trace_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    out.checkpoint_error = checkpoint.error();
    for (uint32_t i = 0; i < n; ++i)
        out.invalid += !out.valid[i];
    return out;
}

namespace
{
// What a ray from a point in the level carries back from the surface it hits (the probes' and the reflection
// probes' rays): emission plus albedo / pi times the lightmap's irradiance at the surface normal there
// (bilinear at the hit's TEXCOORD_1 over the finished lightmap, dilated; the mixed lights' direct light,
// which the lightmap leaves to the run time, included: it still lights what a probe sees). Without surfaces,
// nothing. Throws std::invalid_argument for a lightmap that does not match its atlas, or surfaces without
// lightmap UVs to look it up at.
class LevelRadiance
{
  public:
    LevelRadiance(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                  const LightmapSurfaces* surfaces)
        : mesh_(mesh), surfaces_(surfaces)
    {
        if (sh.texels() != atlas.texels.size() ||
            (!sh.tiles && !sh.mixed_direct.empty() && sh.mixed_direct.size() != sh.texels()))
            throw std::invalid_argument("the lightmap's irradiance does not match its atlas");
        if (surfaces && mesh.uvs1.size() != mesh.positions.size())
            throw std::invalid_argument("probes need lightmap UVs to look the irradiance of a hit up");
        const bool direct = sh.has_direct();
        std::vector<std::array<glm::vec3, 9>> sh9;
        std::vector<std::array<glm::vec3, 4>> directs;
        std::vector<glm::vec3> mixed;
        map_ = dilated(atlas, 1, 2, sh.valid,
                       [&](uint32_t first, std::span<glm::vec3> out)
                       {
                           const uint32_t count = uint32_t(out.size());
                           if (direct)
                           {
                               directs.resize(count);
                               sh.read(first, count, nullptr, directs.data());
                               for (uint32_t i = 0; i < count; ++i)
                                   out[i] = directs[i][0];
                           }
                           else
                           {
                               sh9.resize(count);
                               sh.read(first, count, sh9.data());
                               for (uint32_t i = 0; i < count; ++i)
                                   out[i] = math::sh9_eval_rgb(sh9[i], glm::vec3(0.0f, 0.0f, 1.0f));
                           }
                           if (sh.has_mixed())
                           {
                               mixed.resize(count);
                               sh.read_mixed(first, count, nullptr, mixed.data());
                               for (uint32_t i = 0; i < count; ++i)
                                   out[i] += mixed[i];
                           }
                       });
    }
    // Whether the ray along d met the back of a single-sided surface (which sends no light).
    bool back_face(const EmbreeScene& scene, const RayHit& hit, const glm::vec3& d) const
    {
        return glm::dot(scene.geometric_normal(hit.primitive), d) > 0.0f &&
               !(surfaces_ && surfaces_->double_sided(hit.primitive));
    }
    // The radiance leaving the front of the surface at `hit` (Lambertian: the same towards any direction).
    glm::vec3 surface(const RayHit& hit) const
    {
        if (!surfaces_)
            return glm::vec3(0.0f);
        return surfaces_->emission(hit.primitive, hit.u, hit.v) +
               surfaces_->albedo(hit.primitive, hit.u, hit.v) *
                   atlas_lookup(mesh_, map_, hit.primitive, hit.u, hit.v) / float(M_PI);
    }

  private:
    const io::Mesh& mesh_;
    const LightmapSurfaces* surfaces_;
    io::BlockMaps map_;
};

// A probe's depth map from its rays (direction, distance): per texel the mean distance and its standard
// deviation over the rays in a cos^50 lobe around the texel's centre direction (DDGI's depth sharpness; the
// lobe's half width at half weight is 9.6 degrees), or the nearest ray's distance (deviation 0) where no ray
// falls in the lobe.
void probe_depth_map(std::span<const glm::vec4> rays, std::span<const glm::vec3> texels,
                     std::span<glm::vec2> out)
{
    constexpr float kCutoff = 0.9f; // 0.9^50 = 0.005 of the centre's weight: little left beyond
    for (size_t t = 0; t < texels.size(); ++t)
    {
        double sum = 0.0, mean = 0.0, square = 0.0;
        float nearest = -2.0f;
        glm::vec2 fallback(0.0f);
        for (const glm::vec4& r : rays)
        {
            const float c = glm::dot(texels[t], glm::vec3(r));
            if (c > nearest)
            {
                nearest = c;
                fallback = glm::vec2(r.w, 0.0f);
            }
            if (c <= kCutoff)
                continue;
            const float c2 = c * c, c4 = c2 * c2, c8 = c4 * c4, c16 = c8 * c8, c32 = c16 * c16;
            const double w = double(c32 * c16 * c2); // c^50
            sum += w;
            mean += w * r.w;
            square += w * double(r.w) * r.w;
        }
        if (sum > 0.0)
        {
            mean /= sum;
            out[t] = glm::vec2(float(mean), float(std::sqrt(std::max(square / sum - mean * mean, 0.0))));
        }
        else
            out[t] = fallback;
    }
}
} // namespace

io::LightProbes probe_grid(const io::Mesh& mesh, const glm::uvec3& count)
{
    if (count.x == 0 || count.y == 0 || count.z == 0)
        throw std::invalid_argument("a probe grid needs at least one probe along each axis");
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : mesh.positions)
    {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::vec3 cell = (hi - lo) / glm::vec3(count);
    io::LightProbes g;
    g.count = count;
    g.depth_resolution = kProbeDepthResolution;
    g.lo = lo + 0.5f * cell;
    g.hi = hi - 0.5f * cell;
    return g;
}

void bake_light_probes(io::LightProbes& probes, const io::Mesh& mesh, const LightmapAtlas& atlas,
                       const LightmapSh& sh, const LightmapLights& lights, const LightmapBakeOptions& o,
                       const LightmapSurfaces* surfaces)
{
    check(lights, o);
    const bool scattered = probes.scattered();
    if (scattered)
    {
        if (probes.points.size() > size_t(1) << 24)
            throw std::invalid_argument("scattered probes number 1 to 2^24");
        probes.count = glm::uvec3(uint32_t(probes.points.size()), 1, 1);
        probes.lo = glm::vec3(INFINITY);
        probes.hi = glm::vec3(-INFINITY);
        for (const glm::vec4& q : probes.points)
        {
            if (!std::isfinite(q.x + q.y + q.z) || !(q.w > 0.0f) || !std::isfinite(q.w))
                throw std::invalid_argument(
                    "a scattered probe's position must be finite and its reach positive");
            probes.lo = glm::min(probes.lo, glm::vec3(q));
            probes.hi = glm::max(probes.hi, glm::vec3(q));
        }
    }
    const uint64_t n = io::probe_grid_count(probes.count.x, probes.count.y, probes.count.z);
    if (n == 0)
        throw std::invalid_argument("a probe grid needs 1 to 2^24 probes");
    if (!(probes.lo.x <= probes.hi.x && probes.lo.y <= probes.hi.y && probes.lo.z <= probes.hi.z) ||
        !std::isfinite(probes.lo.x + probes.lo.y + probes.lo.z + probes.hi.x + probes.hi.y + probes.hi.z))
        throw std::invalid_argument("the probe grid's corners must be finite and ordered");
    const LevelRadiance level(mesh, atlas, sh, surfaces); // throws for a lightmap that does not fit
    const EmbreeScene scene(mesh);
    const detail::LightSampler light(lights, o.seed);
    const uint64_t probe_seed = mix64(o.seed ^ 0x50524f4245ull);
    probes.irradiance.assign(size_t(n), {});
    probes.valid.assign(size_t(n), 1);
    // What each probe sees (io::LightProbes::depth), its distances clamped to 1.5 times the diagonal of a
    // grid cell (DDGI's clamp): a point the lookup blends a probe for is at most one diagonal away, so a
    // farther surface only says "visible", and a texel that mixes the sky with a near wall keeps a small
    // deviation. Along an axis of one probe the cell is the scene's extent. Scattered probes: 1.5 times the
    // largest reach.
    const uint32_t resolution = probes.depth_resolution;
    if (resolution > io::kMaxProbeDepthResolution)
        throw std::invalid_argument("a probe's depth map is at most " +
                                    std::to_string(io::kMaxProbeDepthResolution) + " texels a side");
    glm::vec3 lo = glm::min(probes.lo, probes.hi), hi = glm::max(probes.lo, probes.hi);
    for (const glm::vec3& v : mesh.positions)
    {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    glm::vec3 cell;
    for (int a = 0; a < 3; ++a)
        cell[a] =
            probes.count[a] > 1 ? (probes.hi[a] - probes.lo[a]) / float(probes.count[a] - 1) : hi[a] - lo[a];
    float largest = glm::length(cell);
    if (scattered)
    {
        largest = 0.0f;
        for (const glm::vec4& q : probes.points)
            largest = std::max(largest, q.w);
    }
    probes.max_distance = std::max(1.5f * largest, 1e-3f);
    probes.depth.assign(size_t(n) * resolution * resolution, glm::vec2(0.0f));
    std::vector<glm::vec3> texel_directions(size_t(resolution) * resolution);
    for (uint32_t y = 0; y < resolution; ++y)
        for (uint32_t x = 0; x < resolution; ++x)
            texel_directions[size_t(y) * resolution + x] =
                io::octahedral_decode(glm::vec2(float(x) + 0.5f, float(y) + 0.5f) / float(resolution));
    // The mixed lights' occlusion at each probe, in their shadowmask channels.
    const std::vector<ShadowmaskChannel> channels = shadowmask_channels(lights);
    probes.occlusion.assign(channels.empty() ? 0 : size_t(n), {1.0f, 1.0f, 1.0f, 1.0f});
    tbb::parallel_for(
        tbb::blocked_range<uint64_t>(0, n, 1),
        [&](const tbb::blocked_range<uint64_t>& range)
        {
            for (uint64_t at = range.begin(); at != range.end(); ++at)
            {
                const glm::vec3 p = probes.position(size_t(at));
                std::array<glm::dvec3, 9> acc{};
                auto add = [&](const glm::vec3& d, const glm::dvec3& radiance)
                {
                    const math::Sh9 y = math::sh9_eval(d);
                    for (int c = 0; c < 9; ++c)
                        acc[size_t(c)] += radiance * double(y[size_t(c)]);
                };
                int back_faces = 0;
                const double weight = 4.0 * M_PI / double(o.rays);
                std::vector<glm::vec4> seen; // per ray its direction and the distance to what it hit
                if (resolution)
                    seen.resize(size_t(o.rays));
                for (int r = 0; r < o.rays; ++r)
                {
                    const glm::vec3 d = sphere_direction(probe_seed, at, r, o.rays);
                    const std::optional<RayHit> hit = scene.intersect(p, d);
                    if (resolution)
                        seen[size_t(r)] = glm::vec4(d, hit ? std::min(hit->distance, probes.max_distance)
                                                           : probes.max_distance);
                    if (!hit)
                    {
                        if (!light.image_environment())
                            add(d, glm::dvec3(lights.environment_radiance(d)) * weight);
                        continue;
                    }
                    if (level.back_face(scene, *hit, d))
                    {
                        ++back_faces;
                        continue;
                    }
                    if (surfaces)
                        add(d, glm::dvec3(level.surface(*hit)) * weight);
                }
                const uint64_t item =
                    uint64_t(1) << 40 | at; // the light samplers' items, apart from the texels'
                for (int r = 0; r < o.rays && light.image_environment(); ++r)
                {
                    glm::vec3 d;
                    double w = 0.0;
                    if (light.environment_ray(item, r, o.rays, d, w) && !scene.occluded(p, d))
                        add(d, glm::dvec3(lights.environment_radiance(d)) * w);
                }
                // Only baked lights' direct light: a mixed light's is the run time's, a realtime light not
                // baked.
                for (int r = 0; r < o.sun_rays && lights.sun && lights.sun_mode == io::LightMode::Baked; ++r)
                {
                    const glm::vec3 d = light.sun_ray(item, r);
                    if (!scene.occluded(p, d))
                        add(d, glm::dvec3(lights.sun_irradiance) / double(o.sun_rays));
                }
                for (const ShadowmaskChannel& c : channels)
                {
                    // The sun: its rays over the disc not blocked (the whole sphere around a probe); a
                    // punctual light: its one ray, where it reaches.
                    float& share = probes.occlusion[at][size_t(c.channel)];
                    if (c.light < 0)
                    {
                        int visible = 0;
                        for (int r = 0; r < o.sun_rays; ++r)
                            visible += !scene.occluded(p, light.sun_ray(item, r));
                        share *= float(visible) / float(o.sun_rays);
                        continue;
                    }
                    const io::PunctualLight& l = lights.punctual[size_t(c.light)];
                    if (!light_reaches(l, p))
                        continue;
                    glm::vec3 d(0.0f, 0.0f, 1.0f);
                    float distance = INFINITY;
                    light.punctual(l, p, d, distance);
                    share *=
                        distance > 0.0f && !scene.occluded(p, d, 0.0f,
                                                           std::isfinite(distance) ? distance * (1.0f - 1e-4f)
                                                                                   : INFINITY)
                            ? 1.0f
                            : 0.0f;
                }
                for (const io::PunctualLight& l : lights.punctual)
                {
                    if (l.mode != io::LightMode::Baked)
                        continue;
                    glm::vec3 d;
                    float distance = INFINITY;
                    const glm::vec3 e = light.punctual(l, p, d, distance);
                    if (e != glm::vec3(0.0f) &&
                        !scene.occluded(p, d, 0.0f,
                                        std::isfinite(distance) ? distance * (1.0f - 1e-4f) : INFINITY))
                        add(d, glm::dvec3(e));
                }
                math::Sh9Rgb radiance;
                for (int c = 0; c < 9; ++c)
                    radiance[size_t(c)] = glm::vec3(acc[size_t(c)]);
                const math::Sh9Rgb e = math::convolve_cosine(radiance);
                for (int c = 0; c < 9; ++c)
                    probes.irradiance[at][size_t(c)] = e[size_t(c)];
                probes.valid[at] = uint8_t(2 * back_faces <= o.rays);
                if (resolution)
                    probe_depth_map(
                        seen, texel_directions,
                        std::span(probes.depth)
                            .subspan(size_t(at) * texel_directions.size(), texel_directions.size()));
            }
        });
}

io::EnvmapAsset bake_reflection_probe(const io::Mesh& mesh, const LightmapAtlas& atlas, const LightmapSh& sh,
                                      const LightmapLights& lights, const LightmapSurfaces* surfaces,
                                      const glm::vec3& position, const ReflectionProbeOptions& o,
                                      io::ImageRgba* radiance)
{
    LightmapBakeOptions checked;
    check(lights, checked);
    const int side = int(std::lround(std::sqrt(double(std::max(o.rays, 0)))));
    if (o.rays < 1 || o.rays > 4096 || side * side != o.rays)
        throw std::invalid_argument(
            "a reflection probe's rays per pixel must be a square number from 1 to 4096, "
            "not " +
            std::to_string(o.rays));
    EnvmapBakeOptions envmap;
    envmap.size = o.size;
    envmap.exponents = o.exponents;
    check_envmap_options(envmap);
    if (!std::isfinite(position.x + position.y + position.z))
        throw std::invalid_argument("a reflection probe's position must be finite");
    const LevelRadiance level(mesh, atlas, sh, surfaces); // throws for a lightmap that does not fit
    const EmbreeScene scene(mesh);
    const uint32_t w = 4 * o.size, h = 2 * o.size;
    io::ImageRgba image{w, h, std::vector<float>(size_t(w) * h * 4, 1.0f)};
    const uint64_t seed = mix64(o.seed ^ 0x5245464cull);
    auto direction = [&](double u, double v) // u, v in [0, 1] over the image, v from the top
    {
        const double phi = M_PI - 2.0 * M_PI * u, theta = M_PI * v;
        return glm::vec3(
            glm::dvec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    };
    tbb::parallel_for(
        tbb::blocked_range<uint32_t>(0, h, 1),
        [&](const tbb::blocked_range<uint32_t>& rows)
        {
            for (uint32_t y = rows.begin(); y != rows.end(); ++y)
                for (uint32_t x = 0; x < w; ++x)
                {
                    const uint64_t pixel = uint64_t(y) * w + x;
                    glm::dvec3 sum(0.0);
                    for (int r = 0; r < o.rays; ++r)
                    {
                        const double jx = (r % side + uniform01(seed, pixel, 2 * uint64_t(r))) / side,
                                     jy = (r / side + uniform01(seed, pixel, 2 * uint64_t(r) + 1)) / side;
                        const glm::vec3 d = direction((x + jx) / w, (y + jy) / h);
                        const std::optional<RayHit> hit = scene.intersect(position, d);
                        if (!hit)
                            sum += glm::dvec3(lights.environment_radiance(d));
                        else if (!level.back_face(scene, *hit, d))
                            sum += glm::dvec3(level.surface(*hit));
                    }
                    float* p = image.pixels.data() + pixel * 4;
                    for (int c = 0; c < 3; ++c)
                        p[c] = float(sum[c] / o.rays);
                }
        });
    // A baked sun: its disc, far smaller than a pixel, as the irradiance it gives spread over the pixel it
    // lies in (what the pixel's mean radiance is), times the share of the disc the point sees.
    if (lights.sun && lights.sun_mode == io::LightMode::Baked)
    {
        const detail::LightSampler light(lights, o.seed);
        const glm::vec3 towards = glm::transpose(lights.scene_to_world) * lights.sun_direction;
        const int rays = 64;
        int visible = 0;
        for (int r = 0; r < rays; ++r)
            visible += !scene.occluded(position, light.sun_ray(uint64_t(1) << 41, r));
        uint32_t x = 0, y = 0;
        math::equirect_pixel(glm::dvec3(glm::normalize(towards)), w, h, x, y);
        const double solid_angle = 2.0 * M_PI / w * (std::cos(M_PI * y / h) - std::cos(M_PI * (y + 1) / h));
        float* p = image.pixels.data() + (size_t(y) * w + x) * 4;
        for (int c = 0; c < 3; ++c)
            p[c] += float(double(lights.sun_irradiance[c]) * visible / rays / solid_angle);
    }
    io::EnvmapAsset asset = bake_envmap(image, envmap);
    if (radiance)
        *radiance = std::move(image);
    return asset;
}

int lightmap_output_size(std::string_view name)
{
    if (name == "plain")
        return 1;
    if (name == "shadowmask")
        return 4;
    if (name == "rnm")
        return 3;
    return math::basis(name).size; // throws, listing the bases
}

namespace
{
// Every output is a linear map of the SH9 irradiance: K x 9, row-major. "plain" is the row y(+z), "rnm" the
// rows y(B_i) times 2 / (1 + B_i.z), "sh9" the identity, every other basis its hemispherical projection
// (quadrature: computed once per output and kept).
const std::vector<double>& output_matrix(std::string_view name)
{
    static std::mutex lock;
    static std::map<std::string, std::vector<double>, std::less<>> cache;
    std::lock_guard<std::mutex> guard(lock);
    if (const auto it = cache.find(name); it != cache.end())
        return it->second;
    std::vector<double> m;
    auto row = [&](const glm::vec3& d)
    {
        const math::Sh9 y = math::sh9_eval(d);
        m.insert(m.end(), y.begin(), y.end());
    };
    if (name == "plain")
        row(glm::vec3(0.0f, 0.0f, 1.0f));
    else if (name == "rnm")
        for (const glm::vec3& b : math::rnm_basis())
        {
            row(b);
            // Normalised so that uniform radiance 1 over the texel's hemisphere gives pi: E(B_i) is then
            // pi (1 + B_i.z) / 2 (the part of B_i's hemisphere above the surface), B_i.z = 1 / sqrt 3.
            const double scale = 2.0 / (1.0 + double(b.z));
            for (size_t j = m.size() - 9; j < m.size(); ++j)
                m[j] *= scale;
        }
    else
    {
        const math::BasisDesc& basis = math::basis(name); // throws, listing the bases
        if (basis.id == HEMI_BASIS_SH9)
        {
            m.assign(81, 0.0);
            for (int j = 0; j < 9; ++j)
                m[size_t(j) * 10] = 1.0;
        }
        else
            m = math::projection_from_sh9(basis);
    }
    return cache.emplace(std::string(name), std::move(m)).first->second;
}

void apply(const std::vector<double>& m, const std::array<glm::vec3, 9>& e, glm::vec3* out)
{
    for (size_t k = 0; k < m.size() / 9; ++k)
    {
        glm::dvec3 sum(0.0);
        for (size_t j = 0; j < 9; ++j)
            sum += m[k * 9 + j] * glm::dvec3(e[j]);
        out[k] = glm::vec3(sum);
    }
}
} // namespace

std::vector<glm::vec3> lightmap_coefficients(std::string_view name, const std::array<glm::vec3, 9>& e)
{
    const std::vector<double>& m = output_matrix(name);
    std::vector<glm::vec3> out(m.size() / 9);
    apply(m, e, out.data());
    return out;
}

namespace
{
// The normals make_non_negative keeps non-negative: within 75 degrees of the surface's (normal maps tilt
// less). At the horizon itself a basis that holds a linear function (HL2, H4's first band) could only be
// non-negative with no direction left at all.
constexpr double kNonNegativeMinZ = 0.2588190451; // cos 75 degrees

// What make_non_negative evaluates for one output: the basis at 1024 normals spread evenly over that cap
// (a Fibonacci spiral in z, equal areas, so the mean over them is the mean over solid angle); per
// normal j the least change of coefficients (in the hemisphere's L2 norm, the basis's Gram matrix G) that
// raises the irradiance there by 1: G^-1 b_j / (b_j^T G^-1 b_j); and the fit u of the constant 1 with its
// values there, scaled to a mean of 1 over them (the fallback's target).
struct NonNegativeTable
{
    size_t k = 0;
    std::vector<double> basis; // per normal, k values
    std::vector<double> lift;  // per normal, k values
    std::vector<double> unit;  // the constant's fit at each normal
    std::vector<double> u;     // its k coefficients
};

const NonNegativeTable& non_negative_table(std::string_view name)
{
    static std::mutex lock;
    static std::map<std::string, NonNegativeTable, std::less<>> cache;
    std::lock_guard<std::mutex> guard(lock);
    if (const auto it = cache.find(name); it != cache.end())
        return it->second;
    const math::BasisDesc& basis = math::basis(name);
    NonNegativeTable t;
    t.k = size_t(basis.size);
    const Eigen::Index k = Eigen::Index(t.k);
    const std::vector<double> gram = math::gram_matrix(basis);
    const Eigen::MatrixXd g_inverse = Eigen::Map<const Eigen::MatrixXd>(gram.data(), k, k).inverse();
    // The constant 1 is 2 sqrt(pi) y00; its fit is the output matrix's first column times that.
    const std::vector<double>& m = output_matrix(name);
    for (size_t i = 0; i < t.k; ++i)
        t.u.push_back(m[i * 9] * 2.0 * std::sqrt(M_PI));
    const int count = 1024;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    float b[HEMI_BASIS_MAX_SIZE];
    for (int j = 0; j < count; ++j)
    {
        const double z = 1.0 - (j + 0.5) / count * (1.0 - kNonNegativeMinZ), r = std::sqrt(1.0 - z * z);
        basis.eval(glm::vec3(float(r * std::cos(golden * j)), float(r * std::sin(golden * j)), float(z)), b);
        Eigen::VectorXd v(k);
        double unit = 0.0;
        for (size_t i = 0; i < t.k; ++i)
        {
            t.basis.push_back(double(b[i]));
            v[Eigen::Index(i)] = double(b[i]);
            unit += t.u[i] * double(b[i]);
        }
        t.unit.push_back(unit);
        const Eigen::VectorXd w = g_inverse * v;
        const double norm = v.dot(w);
        for (size_t i = 0; i < t.k; ++i)
            t.lift.push_back(norm > 0.0 ? w[Eigen::Index(i)] / norm : 0.0);
    }
    double unit_mean = 0.0;
    for (const double v : t.unit)
        unit_mean += v / double(count);
    for (double& v : t.unit)
        v /= unit_mean;
    for (double& v : t.u)
        v /= unit_mean;
    return cache.emplace(std::string(name), std::move(t)).first->second;
}
} // namespace

bool make_non_negative(std::string_view name, std::span<glm::vec3> c)
{
    const NonNegativeTable& t = non_negative_table(name);
    if (c.size() != t.k)
        throw std::invalid_argument("make_non_negative: output '" + std::string(name) + "' has " +
                                    std::to_string(t.k) + " coefficients, got " + std::to_string(c.size()));
    const size_t normals = t.unit.size();
    bool changed = false;
    std::vector<double> e(normals);
    for (int ch = 0; ch < 3; ++ch)
    {
        std::array<double, HEMI_BASIS_MAX_SIZE> x{};
        for (size_t i = 0; i < t.k; ++i)
            x[i] = double(c[i][ch]);
        auto evaluate = [&]
        {
            double mean = 0.0;
            for (size_t j = 0; j < normals; ++j)
            {
                double sum = 0.0;
                for (size_t i = 0; i < t.k; ++i)
                    sum += x[i] * t.basis[j * t.k + i];
                e[j] = sum;
                mean += sum / double(normals);
            }
            return mean;
        };
        const double mean = evaluate();
        if (!(mean > 0.0))
        {
            for (size_t i = 0; i < t.k; ++i)
            {
                changed = changed || c[i][ch] != 0.0f;
                c[i][ch] = 0.0f;
            }
            continue;
        }
        // Raise the lowest normal to a small floor by the least change that does it, and again, until none
        // is below (each step raises its neighbours too, so a few steps do).
        const double floor = 0.01 * mean;
        bool lifted = false, done = false;
        for (int step = 0; step < 64 && !done; ++step)
        {
            if (step > 0)
                evaluate();
            size_t lowest = 0;
            for (size_t j = 1; j < normals; ++j)
                if (e[j] < e[lowest])
                    lowest = j;
            if (e[lowest] >= 0.5 * floor)
            {
                done = true;
                break;
            }
            const double raise = floor - e[lowest];
            for (size_t i = 0; i < t.k; ++i)
                x[i] += raise * t.lift[lowest * t.k + i];
            lifted = true;
        }
        if (!done)
        {
            // Not settled (it always has been in practice): blend towards the constant of the same mean,
            // x' = a x + (1 - a) m u, as far as needed; a = 0 is the constant itself, which is not negative.
            evaluate();
            double a = 1.0;
            for (size_t j = 0; j < normals; ++j)
            {
                const double safe = mean * t.unit[j];
                if (e[j] < floor * t.unit[j])
                    a = std::min(a, safe > e[j] ? std::max(0.0, (1.0 - 0.01) * safe / (safe - e[j])) : 0.0);
            }
            for (size_t i = 0; i < t.k; ++i)
                x[i] = a * x[i] + (1.0 - a) * mean * t.u[i];
        }
        if (!lifted)
            continue;
        changed = true;
        for (size_t i = 0; i < t.k; ++i)
            c[i][ch] = float(x[i]);
    }
    return changed;
}

struct LightmapOutputBands::Impl
{
    Impl(std::string_view name_, uint32_t width, uint32_t height, std::function<glm::uvec2(uint32_t)> place,
         const LightmapSh& sh_, int dilate, bool non_negative_, TexelChart chart, size_t band_slots)
        : name(name_), k(lightmap_output_size(name_)), sh(sh_), non_negative(non_negative_),
          matrix(name_ == "shadowmask" ? nullptr : &output_matrix(name_)),
          direct((name_ == "plain" || name_ == "rnm") && sh_.has_direct()),
          bands(dilated_grid(width, height, uint32_t(sh_.texels()), place, dilate), uint32_t(sh_.texels()),
                place, k, dilate, sh_.valid, std::move(chart), band_slots)
    {
        if (name == "shadowmask" && !sh.has_mixed())
            throw std::invalid_argument("the bake has no shadowmask (no mixed light)");
    }
    // The K values of texels [first, first + values.size() / K).
    void produce(uint32_t first, std::span<glm::vec3> values, size_t* adjusted)
    {
        const uint32_t count = uint32_t(values.size() / size_t(k));
        if (name == "shadowmask")
        {
            masks.resize(count);
            sh.read_mixed(first, count, masks.data());
            for (size_t i = 0; i < count; ++i)
                for (size_t c = 0; c < 4; ++c)
                    values[i * 4 + c] = glm::vec3(masks[i][c]);
            return;
        }
        // plain and rnm hold irradiance itself: integrated directly where the bake did (LightmapSh::direct).
        if (direct)
        {
            directs.resize(count);
            sh.read(first, count, nullptr, directs.data());
            for (uint32_t i = 0; i < count; ++i)
                for (int j = 0; j < k; ++j)
                    values[i * size_t(k) + size_t(j)] = directs[i][name == "plain" ? 0 : size_t(1 + j)];
            return;
        }
        sh9.resize(count);
        sh.read(first, count, sh9.data());
        for (uint32_t i = 0; i < count; ++i)
        {
            glm::vec3* v = &values[i * size_t(k)];
            apply(*matrix, sh9[i], v);
            // (A texel of the rows around a band is counted with its own band.)
            if (non_negative && name != "plain" && name != "rnm" &&
                make_non_negative(name, std::span<glm::vec3>(v, size_t(k))) && adjusted &&
                first + i >= bands.own_texels().first && first + i < bands.own_texels().second)
                ++*adjusted;
        }
    }

    std::string name;
    int k;
    const LightmapSh& sh;
    bool non_negative;
    const std::vector<double>* matrix; // once, not per texel
    bool direct;
    BandDilation bands;
    std::vector<std::array<glm::vec3, 9>> sh9;
    std::vector<std::array<glm::vec3, 4>> directs;
    std::vector<std::array<float, 4>> masks;
};

LightmapOutputBands::LightmapOutputBands(std::string_view name, uint32_t width, uint32_t height,
                                         std::span<const glm::uvec2> places, const LightmapSh& sh, int dilate,
                                         bool non_negative, std::span<const uint32_t> charts,
                                         size_t band_slots)
{
    if (sh.texels() != places.size() || (!charts.empty() && charts.size() != places.size()))
        throw std::invalid_argument("the lightmap's irradiance does not match its texels' places");
    impl_ = std::make_unique<Impl>(
        name, width, height, [places](uint32_t i) { return places[i]; }, sh, dilate, non_negative,
        charts.empty() ? TexelChart() : TexelChart([charts](uint32_t i) { return charts[i]; }), band_slots);
}

LightmapOutputBands::LightmapOutputBands(std::string_view name, const LightmapAtlas& atlas,
                                         const LightmapSh& sh, int dilate, bool non_negative,
                                         size_t band_slots)
{
    if (sh.texels() != atlas.texels.size())
        throw std::invalid_argument("the lightmap's irradiance does not match its atlas");
    impl_ = std::make_unique<Impl>(
        name, atlas.width, atlas.height, [&atlas](uint32_t i) { return atlas.texels.place(i); }, sh, dilate,
        non_negative, texel_chart(atlas), band_slots);
}

LightmapOutputBands::~LightmapOutputBands() = default;

const io::BlockGrid& LightmapOutputBands::grid() const
{
    return impl_->bands.grid();
}

bool LightmapOutputBands::next(Band& band, size_t* adjusted)
{
    BandDilation::Band b;
    if (!impl_->bands.next(
            [&](uint32_t first, std::span<glm::vec3> values) { impl_->produce(first, values, adjusted); }, b))
        return false;
    band.maps = std::move(b.maps);
    band.first = b.first;
    band.count = b.count;
    band.at = b.at;
    return true;
}

void LightmapOutputBands::restart()
{
    impl_->bands.restart();
}

io::BlockMaps lightmap_maps(std::string_view name, const LightmapAtlas& atlas, const LightmapSh& sh,
                            int dilate, bool non_negative, size_t* adjusted)
{
    LightmapOutputBands bands(name, atlas, sh, dilate, non_negative, SIZE_MAX);
    LightmapOutputBands::Band band;
    bands.next(band, adjusted);
    return std::move(band.maps);
}

io::BlockMaps lightmap_maps(std::string_view name, uint32_t width, uint32_t height,
                            std::span<const glm::uvec2> places, const LightmapSh& sh, int dilate,
                            bool non_negative, size_t* adjusted, std::span<const uint32_t> charts)
{
    LightmapOutputBands bands(name, width, height, places, sh, dilate, non_negative, charts, SIZE_MAX);
    LightmapOutputBands::Band band;
    bands.next(band, adjusted);
    return std::move(band.maps);
}

void LightmapSh::read(uint32_t first, uint32_t count, std::array<glm::vec3, 9>* irr,
                      std::array<glm::vec3, 4>* dir, Noise* noise_out) const
{
    if (uint64_t(first) + count > texels())
        throw std::out_of_range("LightmapSh::read: texels past the lightmap's");
    if ((dir && !has_direct()) || (noise_out && !has_noise()))
        throw std::invalid_argument("LightmapSh::read: the bake made no direct values or noise estimate");
    if (tiles)
    {
        if (irr)
            tiles->read(tiles_copy, 0, first, std::as_writable_bytes(std::span(irr, count)));
        if (dir)
            tiles->read(tiles_copy, 1, first, std::as_writable_bytes(std::span(dir, count)));
        if (noise_out)
            tiles->read(tiles_copy, kNoiseField, first, std::as_writable_bytes(std::span(noise_out, count)));
        return;
    }
    if (irr)
        std::copy_n(irradiance.begin() + first, count, irr);
    if (dir)
        std::copy_n(direct.begin() + first, count, dir);
    if (noise_out)
        std::copy_n(noise.begin() + first, count, noise_out);
}

void LightmapSh::read_mixed(uint32_t first, uint32_t count, std::array<float, 4>* mask_out,
                            glm::vec3* mixed_out) const
{
    if (uint64_t(first) + count > texels())
        throw std::out_of_range("LightmapSh::read_mixed: texels past the lightmap's");
    if (!has_mixed())
        throw std::invalid_argument("LightmapSh::read_mixed: the bake has no mixed light");
    if (tiles)
    {
        if (mask_out)
            tiles->read(0, size_t(tiles_mixed_field), first,
                        std::as_writable_bytes(std::span(mask_out, count)));
        if (mixed_out)
            tiles->read(0, size_t(tiles_mixed_field) + 1, first,
                        std::as_writable_bytes(std::span(mixed_out, count)));
        return;
    }
    if ((mask_out && shadowmask.size() != texels()) || (mixed_out && mixed_direct.size() != texels()))
        throw std::invalid_argument("LightmapSh::read_mixed: the shadowmask or mixed direct light does not "
                                    "match the lightmap's texels");
    if (mask_out)
        std::copy_n(shadowmask.begin() + first, count, mask_out);
    if (mixed_out)
        std::copy_n(mixed_direct.begin() + first, count, mixed_out);
}

void LightmapSh::load()
{
    if (!tiles)
        return;
    const uint32_t n = uint32_t(texels());
    irradiance.resize(n);
    direct.resize(n);
    noise.resize(has_noise() ? n : 0);
    read(0, n, irradiance.data(), direct.data(), noise.empty() ? nullptr : noise.data());
    if (has_mixed())
    {
        shadowmask.resize(n);
        mixed_direct.resize(n);
        read_mixed(0, n, shadowmask.data(), mixed_direct.data());
    }
    tiles.reset();
}

} // namespace hemi::bake
