#pragma once
// Self-shadowed bump maps (Green 2007, "Efficient Self-Shadowed Radiosity Normal Mapping"): per texel, the
// weights of the three radiosity-normal-mapping directions (math::rnm_basis(), Valve's order) with the
// relief's own directional ambient occlusion multiplied in, baked from a height map. Lit by three lightmaps
// in those directions, `albedo * sum_i L_i w_i` (the paper's Eq. 4 and Listing 2) shades the relief with
// soft self-shadows.
//
// Definitions (docs/ssbump.md has them with figures' worth of words; any other implementation can check
// hemi's output against them):
// - The relief is the surface through the texel-centre samples, in units of texel widths: sample (x, y) (x
//   along a row, y down the rows) stands at height `scale * h(x, y)`. Each quad of four neighbouring samples
//   is two triangles split along the diagonal from (x, y) to (x + 1, y + 1).
// - Tangent space: +x along a row, +y up the image (towards row 0, glTF's normal-map convention), +z out of
//   the surface.
// - The normal N at a texel comes from central differences of the (filtered) heights:
//   N = normalize(-scale * dh/dx, scale * dh/dv, 1), dh/dv the difference down the rows.
// - The directional occlusion of direction B_i is O_i = int V(w) max(0, B_i . w) dw / int max(0, B_i . w) dw
//   over the hemisphere z > 0, V the visibility of w from the texel's point on the relief raised by
//   `epsilon` along +z, against the relief, out to `max_distance` texel widths horizontally.
// - The output is w_i = D_i * O_i, with D_i in one of two conventions (SsbumpConvention).
//
// Tiling maps wrap (the relief is periodic, differences wrap). Without wrapping the relief ends at the
// border samples (a ray that leaves the map over the border escapes) and the differences are one-sided
// there.

#include <glm/vec3.hpp>
#include <hemi/bake/distribution.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hemi::io
{
struct Mesh;
}

namespace hemi::bake
{

// Heights, row-major from the top row: 0 is black and 1 white in a PNG; an EXR's values as stored.
struct HeightField
{
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<float> heights;

    float at(uint32_t x, uint32_t y) const { return heights[size_t(y) * width + x]; }
};

// The two conventions of SSBump weights that Valve's own tools write (docs/DESIGN.md, errata):
// - Normalized: D_i = saturate(N . B_i)^2 / sum_j saturate(N . B_j)^2, the paper's Eq. (3) and Valve's
//   normal2ssbump; the weights of a flat texel are 1/3 each and sum to 1 without occlusion.
// - Valve: D_i = saturate(N . B_i), Valve's height2ssbump; a flat texel's are 1/sqrt(3) = 0.577 each, which
//   Source's shaders expect (later Source shaders scale by 0.57735 to reconcile the two kinds).
enum class SsbumpConvention
{
    Normalized,
    Valve,
};
std::string_view to_string(SsbumpConvention convention);
// "normalized" or "valve"; throws std::invalid_argument listing both.
SsbumpConvention parse_ssbump_convention(std::string_view name);

// D of the convention at a unit tangent-space normal (Valve's order, math::rnm_basis()). A normal with no
// positive weight (pointing below every direction, impossible for z > 0) gets D = 0.
glm::vec3 ssbump_weights(const glm::vec3& normal, SsbumpConvention convention);
// The tangent-space normal back from weights (a "bent normal" when occlusion is in them): the exact inverse
// of ssbump_weights for normals inside the cone of the three directions, since sum_i B_i B_i^T = I:
// normalize(sum_i w_i B_i) for Valve's convention, normalize(sum_i sqrt(w_i) B_i) for the normalised one.
// Weights that are all zero give (0, 0, 1).
glm::vec3 ssbump_normal(const glm::vec3& weights, SsbumpConvention convention);

// A bilateral filter (Tomasi & Manduchi 1998) on the heights, against the stair-stepping of 8-bit inputs:
// each height becomes the weighted mean of its (2 radius + 1)^2 window, weight
// exp(-d^2 / (2 (radius/2)^2)) * exp(-(h' - h)^2 / (2 sigma^2)), d the distance in texels and sigma in height
// units ([0, 1] of the input). The window wraps on a tiling map and is clipped at the borders otherwise.
struct BilateralFilter
{
    int radius = 0;     // texels; 0 is off
    float sigma = 0.0f; // height units, > 0 when radius > 0

    bool enabled() const { return radius > 0; }
};
// What hemi-bake applies unless told otherwise: radius 2, sigma 0.02 (five 8-bit steps) for an 8-bit input,
// nothing for deeper ones.
BilateralFilter default_filter(int bits);
// Throws std::invalid_argument for a negative radius, a radius over 64 or a sigma that is not positive.
HeightField bilateral_filter(const HeightField& field, const BilateralFilter& filter, bool wrap);

// Unit tangent-space normals of the relief (central differences, as defined above), row-major.
std::vector<glm::vec3> height_normals(const HeightField& field, float scale, bool wrap);

// The bake's rays of one texel: `rays` directions on the hemisphere z > 0, stratified in A = ssbump_azimuths
// (rays) azimuths (turned by a random angle per texel) and, within each, uniformly in z (jittered strata).
// Ray r lies in azimuth r mod A; every ray of an azimuth shares its direction around z, so one horizon search
// per azimuth answers all of them. weight is the solid angle the ray stands for (the weights sum to 2 pi).
// Counter-based (ray_generator.h): a pure function of (seed, texel, ray, rays).
struct SsbumpRay
{
    glm::vec3 direction;
    float weight;
};
int ssbump_azimuths(int rays);
SsbumpRay ssbump_ray(uint64_t seed, uint64_t texel, int ray, int rays);

// Exact visibility over the relief (a ray that passes between samples does not hit): along one azimuth the
// relief is a polyline whose vertices are where the line crosses the grid lines and the quads' diagonals, so
// a ray of slope k (tan of its elevation) from height z0 is blocked exactly when k < max over those vertices
// of (height - z0) / distance, the horizon. The search walks the crossings outward and skips blocks whose
// maximum height (a max-mip pyramid of the cells) cannot raise the horizon, stopping when even the map's
// highest point could not.
class HeightFieldTracer
{
  public:
    // heights are the (filtered) map's; scale in texel widths per height unit; epsilon the raise of a ray's
    // origin; max_distance (texel widths, > 0) how far rays go horizontally. Throws std::invalid_argument for
    // an empty map, a non-finite height or a scale, epsilon or distance out of range.
    HeightFieldTracer(const HeightField& heights, float scale, bool wrap, float epsilon, float max_distance);

    // max(floor_slope, the horizon slope from texel (x, y) towards the tangent-space direction (dx, dy)): a
    // unit 2D vector, +y up the image.
    double horizon(uint32_t x, uint32_t y, double dx, double dy, double floor_slope) const;
    // Whether the ray from texel (x, y) (raised by epsilon) towards the tangent-space direction (z > 0) meets
    // the relief within max_distance.
    bool occluded(uint32_t x, uint32_t y, const glm::vec3& direction) const;

    float height_at(uint32_t x, uint32_t y) const { return z_[size_t(y) * width_ + x]; } // scaled
    float epsilon() const { return epsilon_; }
    float max_distance() const { return max_distance_; }

  private:
    uint32_t width_, height_;
    bool wrap_;
    float epsilon_, max_distance_;
    float z_max_ = 0.0f;
    std::vector<float> z_;                // scale * heights
    uint32_t cells_x_ = 0, cells_y_ = 0;  // quads: width x height wrapped, one fewer each way otherwise
    std::vector<std::vector<float>> mip_; // mip_[L]: max height over blocks of 2^L x 2^L cells
    std::vector<uint32_t> mip_width_;
};

// The relief as a triangle mesh in tangent space (sample (x, y) at (x, -y, scale * h), the quads split as
// defined above, no wrapping): what the benchmark hands Embree to compare tracers.
io::Mesh height_field_mesh(const HeightField& field, float scale);

struct SsbumpOptions
{
    float scale = 8.0f; // texel widths per height unit (white stands `scale` texels above black)
    int rays = 300;     // per texel (the paper's number)
    bool occlusion = true;
    bool wrap = true;
    SsbumpConvention convention = SsbumpConvention::Normalized;
    BilateralFilter filter; // off unless set (hemi-bake sets default_filter for the input's depth)
    uint64_t seed = 1;
    float epsilon = 1e-3f;     // texel widths
    float max_distance = 0.0f; // texel widths; 0: the map's larger side
    // Checkpoints (checkpoint.h): empty is off. The bake of hemi-bake writes OUT.png.partial.
    std::filesystem::path checkpoint;
    double checkpoint_seconds = 30.0;
    // Who computes the rows (distribution.h): null, this process; else the ranks of a job, which all call
    // bake_ssbump with the same arguments and all return the same map. Only the leader resumes and saves
    // the checkpoint and reports progress.
    Distribution* distribution = nullptr;
};
// Throws std::invalid_argument naming the option that is out of range.
void check_ssbump_options(const SsbumpOptions& options);

// Bytes a bake of a height map of `texels` texels takes at its peak (the decoded image, the heights and their
// filtered copy, normals, occlusion and weights, the horizon tracer, the 8-bit output), for refusing a map
// the machine cannot hold before it is read (io::check_memory).
uint64_t ssbump_memory(uint64_t texels, const SsbumpOptions& options);

struct SsbumpProgress
{
    uint64_t texels_done = 0;
    uint64_t texels = 0;
    std::string checkpoint_error; // non-empty once saving a checkpoint failed (the bake goes on)
};

struct SsbumpMap
{
    uint32_t width = 0, height = 0;
    SsbumpConvention convention = SsbumpConvention::Normalized;
    std::vector<glm::vec3> weights;   // w_i = D_i O_i, row-major
    std::vector<glm::vec3> occlusion; // O_i (1 without occlusion)
    std::vector<glm::vec3> normals;   // N
    // Statistics of the bake.
    uint64_t rays = 0;
    double trace_seconds = 0.0;
    bool resumed = false;
    std::string checkpoint_error;
};

// Bakes the map: multi-threaded (TBB) and deterministic, the same bytes on any thread count and after a
// resume. progress, when given, is called on the calling thread between slices of texels. Throws
// std::invalid_argument for an empty or non-finite height field or bad options.
SsbumpMap bake_ssbump(const HeightField& field, const SsbumpOptions& options,
                      const std::function<void(const SsbumpProgress&)>& progress = {});

// Weights of a tangent-space normal map (the paper's conversion from Listing 1 to Listing 2, no occlusion).
SsbumpMap ssbump_from_normals(uint32_t width, uint32_t height, std::span<const glm::vec3> normals,
                              SsbumpConvention convention);

// Which channel of an image holds the heights: grey (an image whose R, G and B are equal, or a grey PNG), or
// one channel (Valve's height2ssbump reads alpha).
enum class HeightChannel
{
    Grey,
    R,
    G,
    B,
    A,
};
// "grey", "r", "g", "b" or "a"; throws std::invalid_argument listing them.
HeightChannel parse_height_channel(std::string_view name);

struct HeightMapFile
{
    HeightField field;
    int bits = 0; // 8 or 16 (PNG), 32 (EXR)
    std::vector<uint8_t>
        alpha; // the file's alpha when it has one and the heights are not in it (kept in the output)
};
// Reads a height map: an 8- or 16-bit PNG or an EXR. Throws io::FormatError naming the file when it cannot be
// read, has a non-finite value, or when the channel does not hold heights: a colour image read as grey, a
// channel the file lacks, a constant alpha, or what looks like a tangent-space normal map (then the message
// says to use --from-normal).
HeightMapFile read_height_map(const std::filesystem::path& path, HeightChannel channel);
// Reads a tangent-space normal map (PNG, n = 2 c - 1, normalised; zero vectors read as (0, 0, 1) and are
// counted in *zero_normals). Throws io::FormatError naming the file when it cannot be read or does not look
// like a normal map (most texels must be near unit length with z > 0).
std::vector<glm::vec3> read_normal_map(const std::filesystem::path& path, uint32_t& width, uint32_t& height,
                                       std::vector<uint8_t>& alpha, size_t* zero_normals = nullptr);

// 8-bit RGBA: the weights (or a normal map's n * 0.5 + 0.5) rounded to 8 bits, alpha from `alpha` when it is
// not empty, else 255.
std::vector<uint8_t> ssbump_rgba8(std::span<const glm::vec3> values, std::span<const uint8_t> alpha,
                                  bool signed_normal);

} // namespace hemi::bake
