#pragma once
// The bake side of Heidrich & Seidel 1999: factored BRDF lookup tables (hemi-bake brdf) and parabolic
// environment maps with their mipmaps, prefiltered glossy and diffuse maps and Fresnel tables (hemi-bake
// envmap). The models and maps themselves live in the math layer (math/brdf.h, math/paraboloid.h); this layer
// chooses parameters, measures errors and writes files.

#include <hemi/io/envmap_asset.h>
#include <hemi/io/image.h>
#include <hemi/math/brdf.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace hemi::bake
{

struct BrdfBakeOptions
{
    std::string model = "torrance-sparrow"; // torrance-sparrow | banks | phong | blinn-phong | cosine-lobe
    std::string distribution = "beckmann";  // torrance-sparrow: beckmann | gaussian
    double roughness = 0.3;                 // torrance-sparrow: m
    double ior = 1.5;                       // torrance-sparrow: index of refraction (> 1)
    double exponent = 50.0;                 // banks, phong, blinn-phong, cosine-lobe
    uint32_t size = 256;                    // samples per table axis
    bool eight_bit = false; // store each channel as round(255 v / max) / 255 with max in metadata
};

// How far the tables' product (bilinear lookups, as a GPU's sampler makes them) is from the model evaluated
// directly, over a dense set of directions: relative error |table - direct| / max(direct, 1% of the set's
// largest direct value). The set: l and v each at 1024 directions of the hemisphere (32 cosines at interval
// midpoints x 32 azimuths; n = +z, Banks' t = +x), every pair. "bulk" is every pair with cos_alpha >= 0.1 and
// cos_beta >= 0.1, "grazing" the rest (where the paper notes the singularity of G / cos_beta).
struct BrdfError
{
    double bulk_max = 0.0, bulk_rms = 0.0;
    double grazing_max = 0.0, grazing_rms = 0.0;
    uint64_t bulk_samples = 0, grazing_samples = 0;
};

struct BrdfBake
{
    std::vector<math::BrdfTable> tables; // as stored (8-bit codes / 255 when eight_bit)
    std::vector<std::vector<double>>
        scales;            // per table, per channel: stored value x scale = the model's value
    BrdfError error;       // of what is stored (with --8bit: of the quantised tables)
    BrdfError float_error; // of the float tables (equal to error without --8bit)
};

// Validates the options (std::invalid_argument naming the option: an unknown model or distribution, ior <= 1,
// roughness <= 0, exponent <= 0, NaN, a size outside [2, 8192]), builds the tables and measures their errors.
BrdfBake bake_brdf(const BrdfBakeOptions& options);
// Writes the tables as one EXR (float channels named "<channel>" for one table, or the tables' channels for
// Torrance-Sparrow's two: "FD", "G"), with the model, its parameters, each channel's axes and scale and the
// sampling convention as string attributes "hemi.*" (docs: README, hemi-bake brdf). Atomic.
void write_brdf_exr(const std::filesystem::path& path, const BrdfBakeOptions& options, const BrdfBake& bake);

struct EnvmapBakeOptions
{
    uint32_t size = 512;                          // level 0 of each half: a power of two
    std::vector<double> exponents{10, 100, 1000}; // Phong exponents of the glossy maps
    std::vector<double> iors{1.5};                // indices of refraction of the Fresnel tables
    uint32_t fresnel_samples = 256;
    // The brute-force sum over every texel of each lobe's cap (math::prefilter_phong_exact) instead of the
    // faster sum over coarser texels at every other texel (math::prefilter_phong, within 0.5% RMSE of it).
    bool exact = false;
};

struct EnvmapBakeStats
{
    double resample_seconds = 0.0, mip_seconds = 0.0, diffuse_seconds = 0.0;
    std::vector<double> glossy_seconds; // per exponent
    std::vector<uint64_t> glossy_pairs; // lobe evaluations per exponent
};

// Validates the options and the environment (std::invalid_argument: a size that is not a power of two in
// [8, 4096], an exponent <= 0 or NaN, an ior <= 1 or NaN, an image that is not 2:1 or not finite) and bakes.
// progress(stage) is called before each stage (may be empty).
io::EnvmapAsset bake_envmap(const io::ImageRgba& equirect, const EnvmapBakeOptions& options,
                            EnvmapBakeStats* stats = nullptr,
                            const std::function<void(const std::string&)>& progress = {});
// The options' checks alone (what bake_envmap throws for them), for the command line to run before reading
// the environment.
void check_envmap_options(const EnvmapBakeOptions& options);

// The comparison report's measurements (hemi-bake envmap --report): for each prefiltered map of the asset
// (the diffuse map as exponent 1, then each glossy map), its parabolic lookup and a cube-map implementation
// of the same filter against the reference, at `directions` reflection directions spread evenly over the
// sphere (a Fibonacci lattice). The reference is Eq. 9 integrated over every pixel of the source equirect
// where the lobe exceeds 1e-4 of its peak (each pixel at its centre with its exact solid angle): a ray per
// pixel, what a ray tracer converges to. The cube map has faces of half the parabolic map's size (the same
// largest texel), resampled from the same equirect and filtered by the same windowed sum (math::PhongLobe)
// over its own texels, and is looked up bilinearly with seamless filtering across its faces.
struct PrefilterComparison
{
    double exponent = 0.0;
    uint32_t parabolic_size = 0, cube_size = 0; // per side: each half, each face
    uint64_t parabolic_texels = 0, cube_texels = 0;
    double parabolic_rmse = 0.0, cube_rmse = 0.0; // of the luminance-free mean over RGB, in radiance
    double reference_rms = 0.0;                   // RMS of the reference, for relative errors
    double cube_seconds = 0.0;                    // resampling the equirect into the cube and filtering it
};
std::vector<PrefilterComparison> compare_prefiltered_maps(const io::ImageRgba& equirect,
                                                          const io::EnvmapAsset& asset,
                                                          uint32_t directions = 1024);
// The reference alone: Eq. 9 for Phong exponent e integrated over the equirect's pixels, at each direction.
std::vector<glm::dvec3> phong_reference(const io::ImageRgba& equirect, double exponent,
                                        std::span<const glm::dvec3> directions);

// One half of a parabolic map as an image: its texels' RGB, alpha 1 inside the circle the half owns (as the
// paper marks it), 0 outside.
io::ImageRgba parabolic_half_image(const math::ParabolicImage& map, int half);

// Writes every image of the asset as EXR into `dir` (created): mirror_L<level>_<front|back>.exr,
// glossy_e<exponent>_<front|back>.exr, diffuse_<front|back>.exr and fresnel.exr (one row, a channel per ior
// named "ior<value>"). Returns the paths written.
std::vector<std::filesystem::path> write_envmap_exrs(const std::filesystem::path& dir,
                                                     const io::EnvmapAsset& asset);

} // namespace hemi::bake
