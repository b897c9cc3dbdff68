#pragma once
// Lightmap UVs (glTF TEXCOORD_1) turned into the texels a lightmap bake traces from: validation with a clear
// report, and conservative rasterisation in lightmap UV space.
//
// Conventions: texel (x, y) of a W x H atlas covers u in [x / W, (x + 1) / W] and v in [y / H, (y + 1) / H],
// rows from the top (v = 0, glTF's image origin), as render::TexelCoefficients samples them.
//
// Every texel that a triangle's UV footprint touches is covered (conservative rasterisation: the triangle
// and the texel's square overlap, not only the centre). A texel whose centre lies inside a triangle samples
// that point; one that the triangle only grazes samples the centroid of the triangle's part inside the
// texel's square, so every sample is on the surface and inside the texel's footprint. Where several
// triangles touch a texel, the one containing the centre wins, else the one whose sample is nearest the
// centre (ties: the lower triangle index), so the result does not depend on the order of the work.
//
// Overlaps are texel centres that two triangles claim under a fill rule that gives a point on a shared edge
// (or vertex) to exactly one of the triangles meeting there: a chart's own triangles never overlap. Shipped
// levels have them: Quake III's q3map2 stores one lightmap rectangle for surfaces that came out lit the same
// (copies of a wall, mirrored corridors) and lays decals over walls on the same texels; a face modelled
// twice back to back on one rectangle does it too. So they are reported as a warning and resolved
// deterministically: each contested texel goes to the triangle whose plane its uncontested neighbours share,
// else the one facing into the scene (towards the area-weighted centroid of its surfaces: of a back-to-back
// pair, the face on the level's inside), else the lower index; it samples the centre. The others draw that
// triangle's light.
//
// The frame of a texel is the tangent frame of the normal-map UV set (Habel & Wimmer 2010, Sec. 4.3): the
// interpolated vertex normal, the interpolated tangent made orthogonal to it, and the bitangent
// cross(N, T) * tangent.w, as glTF defines it. Lightmap coefficients live in that frame, so that the runtime
// evaluates them at the normal-map normal with no further transform.

#include <hemi/bake/paged_array.h>
#include <hemi/io/block_maps.h>
#include <hemi/io/mesh.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <compare>
#include <iterator>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace hemi::bake
{

struct LightmapTexel
{
    uint32_t x = 0, y = 0;
    uint32_t triangle = 0;
    glm::vec3 barycentric{1.0f, 0.0f,
                          0.0f};           // of the sample point, weights of the triangle's vertices 0, 1, 2
    bool centre_inside = false;            // the texel centre lies in the triangle (else: a grazed texel)
    glm::vec3 position{0.0f};              // the sample point on the surface (mesh units)
    glm::vec3 normal{0.0f, 0.0f, 1.0f};    // unit, the frame's z
    glm::vec3 tangent{1.0f, 0.0f, 0.0f};   // unit, the frame's x
    glm::vec3 bitangent{0.0f, 1.0f, 0.0f}; // unit, the frame's y
    glm::vec3 geometric_normal{0.0f, 0.0f, 1.0f}; // unit normal of the triangle (counter-clockwise front)
    float world_size = 0.0f; // the texel's footprint on the surface: sqrt(world area / texel area)
    uint32_t chart = 0;      // its triangle's chart (lightmap_charts): what may fill it when it is invalid
};

// The covered texels of an atlas, in row-major order of (y, x), each kept in 16 bytes (its place, its
// triangle, the barycentrics of its sample point) and given out as a whole LightmapTexel, its frame, point
// and size computed from the mesh it was rasterised from when asked for (in double, the same arithmetic each
// time: the same texel gives the same bytes). The 96 bytes of a LightmapTexel a covered texel were the
// largest part of a bake's memory after the sums; now the bake and its outputs hold 16 (issue 45).
//
// It refers to the mesh's arrays (positions, normals, tangents, indices, lightmap UVs) as a span does: the
// mesh must outlive the atlas and keep those arrays unchanged (moving the mesh keeps them).
class LightmapTexels
{
  public:
    // A texel as kept: x and y (an atlas side is at most 65536), the triangle with the "centre inside" flag
    // in its top bit, and the sample point's barycentric weights of vertices 1 and 2 (vertex 0's is the
    // rest).
    struct Packed
    {
        uint16_t x = 0, y = 0;
        uint32_t triangle = 0;
        float b1 = 0.0f, b2 = 0.0f;
    };
    static constexpr uint32_t kCentreInside = 0x80000000u;

    class Iterator
    {
      public:
        using iterator_category = std::random_access_iterator_tag;
        using value_type = LightmapTexel;
        using difference_type = std::ptrdiff_t;
        using pointer = void;
        using reference = LightmapTexel;

        Iterator() = default;
        Iterator(const LightmapTexels* texels, size_t i) : texels_(texels), i_(i) {}
        LightmapTexel operator*() const { return (*texels_)[i_]; }
        LightmapTexel operator[](difference_type d) const
        {
            return (*texels_)[size_t(difference_type(i_) + d)];
        }
        Iterator& operator++() { return ++i_, *this; }
        Iterator operator++(int) { return {texels_, i_++}; }
        Iterator& operator--() { return --i_, *this; }
        Iterator operator--(int) { return {texels_, i_--}; }
        Iterator& operator+=(difference_type d) { return i_ = size_t(difference_type(i_) + d), *this; }
        Iterator& operator-=(difference_type d) { return i_ = size_t(difference_type(i_) - d), *this; }
        Iterator operator+(difference_type d) const { return {texels_, size_t(difference_type(i_) + d)}; }
        Iterator operator-(difference_type d) const { return {texels_, size_t(difference_type(i_) - d)}; }
        difference_type operator-(const Iterator& o) const
        {
            return difference_type(i_) - difference_type(o.i_);
        }
        bool operator==(const Iterator& o) const { return i_ == o.i_; }
        auto operator<=>(const Iterator& o) const { return i_ <=> o.i_; }

      private:
        const LightmapTexels* texels_ = nullptr;
        size_t i_ = 0;
    };

    LightmapTexels() = default;
    // The texels of a width x height atlas over `mesh` (rasterize_lightmap makes them), with each triangle's
    // chart.
    LightmapTexels(const io::Mesh& mesh, uint32_t width, uint32_t height, PagedArray<Packed> packed,
                   std::vector<uint32_t> charts);

    size_t size() const { return packed_.size(); }
    bool empty() const { return packed_.empty(); }
    Iterator begin() const { return {this, 0}; }
    Iterator end() const { return {this, packed_.size()}; }

    // Texel i whole (computed: about a hundred operations in double).
    LightmapTexel operator[](size_t i) const;
    // What is kept of it, without the computing.
    glm::uvec2 place(size_t i) const
    {
        const Packed k = packed_[i];
        return {k.x, k.y};
    }
    uint32_t triangle(size_t i) const { return packed_[i].triangle & ~kCentreInside; }
    uint32_t chart(size_t i) const { return charts_[triangle(i)]; }
    glm::vec3 geometric_normal(size_t i) const; // its triangle's (LightmapTexel::geometric_normal)
    // Each triangle's chart (lightmap_charts).
    std::span<const uint32_t> charts() const { return charts_; }
    // Where the records are: in memory or in pages of a temporary file (LightmapAtlasStorage).
    const PagedStore& store() const { return packed_.store(); }
    // The records brought into memory (from pages of a file, read back in order).
    void keep_in_memory() { packed_ = packed_.in_memory(); }

  private:
    PagedArray<Packed> packed_;
    std::vector<uint32_t> charts_; // per triangle
    uint32_t width_ = 0, height_ = 0;
    std::span<const glm::vec3> positions_, normals_;
    std::span<const glm::vec4> tangents_;
    std::span<const glm::vec2> uvs1_;
    std::span<const uint32_t> indices_;
};

// The covered texels and where they are. Its memory follows the covered texels: only the 8 x 8 blocks of the
// atlas that some triangle touches are kept (io::BlockGrid), and 20 bytes a covered texel (its record and its
// slot's index), in memory or, for a bake larger than its memory budget, in pages of temporary files
// (LightmapAtlasStorage).
struct LightmapAtlas
{
    uint32_t width = 0, height = 0;
    io::BlockGrid grid;             // the blocks that triangles touch
    PagedArray<int32_t> slot_texel; // per slot of grid: index into texels, or -1
    LightmapTexels texels;          // covered texels, in row-major order of (y, x)

    // Index into texels of texel (x, y), or -1 for an empty texel (or one outside the atlas).
    int32_t texel_of(int64_t x, int64_t y) const
    {
        const int64_t s = grid.slot(x, y);
        return s < 0 ? -1 : slot_texel[size_t(s)];
    }
};

// The blocks of a width x height atlas that the mesh's lightmap UVs touch (what rasterize_lightmap keeps),
// to know a bake's memory before it is spent. The mesh is checked as rasterize_lightmap checks it.
io::BlockGrid lightmap_blocks(const io::Mesh& mesh, uint32_t width, uint32_t height);

// What is wrong or notable in a mesh's lightmap UVs.
struct LightmapUvReport
{
    size_t triangles = 0;
    size_t outside = 0;            // triangles with a lightmap UV outside [0, 1]
    size_t degenerate = 0;         // triangles of zero area in lightmap UV space (no texel can see them)
    size_t zero_area = 0;          // triangles of zero area in space (ignored)
    size_t overlapping_texels = 0; // texel centres inside two or more triangles
    uint32_t overlap_example[2] = {0, 0}; // two triangles that overlap, when overlapping_texels > 0
    std::vector<glm::uvec2> overlaps;     // those texels, in row-major order of blocks
    size_t grazed_instead = 0; // texels whose claimants lie inside geometry, given to another chart's
                               // triangle that grazes them and does not (rasterize_lightmap)
    size_t covered_texels = 0;
    // Texel density: the world size of a texel, per primitive range of triangles (all triangles when the
    // caller passes none), min and max over those with UV area.
    float min_texel_size = 0.0f, max_texel_size = 0.0f;
    // One line each, with counts and an example. Problems make the lightmap impossible (none at present);
    // warnings lose or waste texels (overlapping UVs, resolved as above; UVs outside [0, 1], triangles of no
    // UV area, texel density varying more than 4x between primitives).
    std::vector<std::string> problems;
    std::vector<std::string> warnings;

    bool ok() const { return problems.empty(); }
};

// Where rasterize_lightmap keeps the atlas's texel records and slot indices: in memory (no directory), or in
// two temporary files in `directory`, each read back through a cache of `cache_pages` pages of
// PagedStore::kPageItems items (PagedStore: the files are gone from the directory as soon as they are made).
struct LightmapAtlasStorage
{
    static constexpr size_t kDefaultCachePages = 256;
    std::filesystem::path directory;
    size_t cache_pages = kDefaultCachePages;
};

struct TriangleRange
{
    uint32_t first = 0, count = 0; // triangles [first, first + count)
    std::string name;              // for the report
};

// Validates and rasterises in one pass. The mesh needs positions, normals, tangents and uvs1 (Throws
// std::invalid_argument naming what is missing, or for a size of 0 or over 16384). `ranges` groups the
// triangles for the density report (glTF primitives); empty is one group.
//
// A texel centre that several triangles claim (overlapping UVs) goes to one of them: first to one whose
// point there does not lie inside geometry as the bake judges a texel (hemisphere rays, most of which
// meet the backs of single-sided surfaces; `double_sided`, per triangle, marks those whose back counts as
// a front; empty: none), then to the one whose chart continues there, then to the one facing the scene's
// centre. Where every triangle claiming a centre lies inside geometry there, another chart's triangle that
// grazes the texel (covers part of it, not its centre) and does not takes it (q3map2's unpadded lightmap
// pages put faces side by side). Only meshes with overlaps or charts that share texels pay for the rays (and
// an Embree scene of the mesh); of a texel that more than 64 triangles claim (a pile of copies over one UV
// square) only the first 64 are candidates.
//
// Each candidate takes kOverlapCandidateBytes while the overlaps are resolved. `overlap_budget` bounds them:
// when the candidates would take more (a mesh instanced many times over one set of lightmap UVs), throws
// std::length_error saying how many texels overlap and how much they need, as soon as they exceed it, before
// any ray is traced. 0: no bound.
//
// The rasteriser's tables take kRasterTableBytesPerSlot a slot of the atlas's touched blocks. With
// `band_slots`, they cover one band of whole block rows of at most that many slots at a time (at least one
// row), with the block row above and below it, each triangle that touches the band rasterised into it: the
// atlas then holds each slot's texel index (4 bytes) and each covered texel's record (16), and the tables one
// band (a bake in tiles under a memory budget). The same atlas and report for any band size; 0: the whole
// atlas at once. The candidates and their bound are then a band's. `storage`: where the records and slot
// indices go (in memory, or in pages of files: the same atlas).
constexpr uint64_t kOverlapCandidateBytes =
    16 + 1; // (slot, triangle) and the judge's answer, claimant or grazer
constexpr uint64_t kRasterTableBytesPerSlot =
    4 + 8 + 8 + 1 + 4 + 4; // best triangle, distance, barycentrics, claims, first claimant, texel index
LightmapAtlas rasterize_lightmap(const io::Mesh& mesh, uint32_t width, uint32_t height,
                                 LightmapUvReport& report, const std::vector<TriangleRange>& ranges = {},
                                 std::span<const uint8_t> double_sided = {}, uint64_t overlap_budget = 0,
                                 size_t band_slots = 0, const LightmapAtlasStorage& storage = {});
// The atlas refers to the mesh's arrays (LightmapTexels): not of a temporary mesh.
LightmapAtlas rasterize_lightmap(io::Mesh&& mesh, uint32_t width, uint32_t height, LightmapUvReport& report,
                                 const std::vector<TriangleRange>& ranges = {},
                                 std::span<const uint8_t> double_sided = {}, uint64_t overlap_budget = 0,
                                 size_t band_slots = 0, const LightmapAtlasStorage& storage = {}) = delete;

} // namespace hemi::bake
