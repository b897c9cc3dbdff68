// Quake III BSP levels out of OpenArena's .pk3 archives, as glTF scenes for the lightmap tests (q3_level.h).
// The formats as their specifications give them: PKWARE's APPNOTE for the zip container (end of central
// directory, central directory, local headers; raw deflate through zlib) and the IBSP 46 lump layout that
// Quake III's qfiles.h defines (dheader_t, dsurface_t, drawVert_t).
#include "q3_level.h"

#include <glm/geometric.hpp>

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace hemi::test
{
namespace
{

uint32_t u16(const uint8_t* p)
{
    return uint32_t(p[0]) | uint32_t(p[1]) << 8;
}
uint32_t u32(const uint8_t* p)
{
    return u16(p) | u16(p + 2) << 16;
}
int32_t i32(const uint8_t* p)
{
    const uint32_t u = u32(p);
    int32_t v;
    std::memcpy(&v, &u, 4);
    return v;
}
float f32(const uint8_t* p)
{
    const uint32_t u = u32(p);
    float v;
    std::memcpy(&v, &u, 4);
    return v;
}

// `size` bytes at `offset` of the open file, or an error naming it.
std::vector<uint8_t> read_at(std::ifstream& f, const std::string& name, uint64_t offset, size_t size)
{
    std::vector<uint8_t> bytes(size);
    f.clear();
    f.seekg(std::streamoff(offset));
    f.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size));
    if (!f || size_t(f.gcount()) != size)
        throw std::runtime_error(name + ": cannot read " + std::to_string(size) + " bytes at offset " +
                                 std::to_string(offset));
    return bytes;
}

// Entries larger than this are refused before anything is allocated for them (the largest OpenArena map
// is 10 MB).
constexpr uint64_t kMaxEntryBytes = uint64_t(256) << 20;

} // namespace

std::vector<uint8_t> read_zip_entry(const std::filesystem::path& zip, const std::string& name)
{
    const std::string file = zip.string();
    std::ifstream f(zip, std::ios::binary);
    if (!f)
        throw std::runtime_error(file + ": cannot open the archive (is the openarena-081-maps package "
                                        "installed? bash cmake/install_deps.sh installs it)");
    f.seekg(0, std::ios::end);
    const uint64_t size = uint64_t(f.tellg());

    // The end of central directory record: 22 bytes and a comment of at most 65535, at the end of the file.
    const size_t tail_size = size_t(std::min<uint64_t>(size, 22 + 65535));
    const std::vector<uint8_t> tail = read_at(f, file, size - tail_size, tail_size);
    size_t eocd = SIZE_MAX;
    for (size_t i = tail_size >= 22 ? tail_size - 22 + 1 : 0; i-- > 0;)
        if (u32(&tail[i]) == 0x06054b50)
        {
            eocd = i;
            break;
        }
    if (eocd == SIZE_MAX)
        throw std::runtime_error(file + ": not a zip archive (no end of central directory record)");
    const uint32_t entries = u16(&tail[eocd + 10]);
    const uint32_t directory_size = u32(&tail[eocd + 12]), directory_offset = u32(&tail[eocd + 16]);
    if (entries == 0xffff || directory_offset == 0xffffffffu)
        throw std::runtime_error(file + ": ZIP64 archives are not supported");
    if (uint64_t(directory_offset) + directory_size > size)
        throw std::runtime_error(file + ": the central directory lies outside the file");
    const std::vector<uint8_t> directory = read_at(f, file, directory_offset, directory_size);

    const std::string entry = file + ":" + name;
    for (size_t p = 0, e = 0; e < entries; ++e)
    {
        if (p + 46 > directory.size() || u32(&directory[p]) != 0x02014b50)
            throw std::runtime_error(file + ": central directory entry " + std::to_string(e) +
                                     " is malformed");
        const uint32_t flags = u16(&directory[p + 8]), method = u16(&directory[p + 10]);
        const uint32_t crc = u32(&directory[p + 16]);
        const uint32_t packed_size = u32(&directory[p + 20]), unpacked_size = u32(&directory[p + 24]);
        const size_t name_size = u16(&directory[p + 28]), extra_size = u16(&directory[p + 30]),
                     comment_size = u16(&directory[p + 32]);
        const uint32_t local_offset = u32(&directory[p + 42]);
        if (p + 46 + name_size > directory.size())
            throw std::runtime_error(file + ": central directory entry " + std::to_string(e) +
                                     " is malformed");
        const std::string entry_name(reinterpret_cast<const char*>(&directory[p + 46]), name_size);
        p += 46 + name_size + extra_size + comment_size;
        if (entry_name != name)
            continue;

        if (flags & 1)
            throw std::runtime_error(entry + ": encrypted entries are not supported");
        if (packed_size == 0xffffffffu || unpacked_size == 0xffffffffu || local_offset == 0xffffffffu)
            throw std::runtime_error(entry + ": ZIP64 entries are not supported");
        if (method != 0 && method != 8)
            throw std::runtime_error(entry + ": compression method " + std::to_string(method) +
                                     " is not supported (only stored and deflated)");
        if (unpacked_size > kMaxEntryBytes || (method == 0 && packed_size != unpacked_size))
            throw std::runtime_error(entry + ": implausible size " + std::to_string(unpacked_size));
        // The local header repeats the name and has an extra field of its own; the data follow them.
        const std::vector<uint8_t> local = read_at(f, entry, local_offset, 30);
        if (u32(&local[0]) != 0x04034b50)
            throw std::runtime_error(entry + ": the local header is malformed");
        const uint64_t data_offset = uint64_t(local_offset) + 30 + u16(&local[26]) + u16(&local[28]);
        if (data_offset + packed_size > size)
            throw std::runtime_error(entry + ": the data lie outside the file");
        std::vector<uint8_t> packed = read_at(f, entry, data_offset, packed_size);

        std::vector<uint8_t> bytes;
        if (method == 0)
            bytes = std::move(packed);
        else
        {
            bytes.resize(unpacked_size);
            z_stream z{};
            if (inflateInit2(&z, -MAX_WBITS) != Z_OK)
                throw std::runtime_error(entry + ": zlib's inflateInit2 failed");
            z.next_in = packed.data();
            z.avail_in = uInt(packed.size());
            z.next_out = bytes.data();
            z.avail_out = uInt(bytes.size());
            const int status = inflate(&z, Z_FINISH);
            const uLong produced = z.total_out;
            inflateEnd(&z);
            if (status != Z_STREAM_END || produced != unpacked_size)
                throw std::runtime_error(entry + ": the deflated data are corrupt (zlib status " +
                                         std::to_string(status) + ", " + std::to_string(produced) + " of " +
                                         std::to_string(unpacked_size) + " bytes)");
        }
        if (uint32_t(crc32(0, bytes.data(), uInt(bytes.size()))) != crc)
            throw std::runtime_error(entry + ": CRC-32 mismatch");
        return bytes;
    }
    throw std::runtime_error(entry + ": no such entry in the archive");
}

namespace
{

// IBSP 46: the lumps this converter reads, and the sizes of their records.
enum Lump
{
    kTextures = 1,
    kVertexes = 10,
    kMeshverts = 11,
    kFaces = 13,
    kLightmaps = 14,
    kLumpCount = 17,
};
constexpr size_t kTextureBytes = 72, kVertexBytes = 44, kFaceBytes = 104;
constexpr size_t kLightmapSide = 128, kLightmapBytes = kLightmapSide * kLightmapSide * 3;

enum FaceType
{
    kPolygon = 1,
    kPatch = 2,
    kMesh = 3,
    kBillboard = 4,
};

// One vertex as the BSP stores it (drawVert_t), Quake's axes and units.
struct BspVertex
{
    glm::vec3 position;
    glm::vec2 uv, lightmap_uv;
    glm::vec3 normal;
};

BspVertex operator*(float w, const BspVertex& v)
{
    return {w * v.position, w * v.uv, w * v.lightmap_uv, w * v.normal};
}
BspVertex operator+(const BspVertex& a, const BspVertex& b)
{
    return {a.position + b.position, a.uv + b.uv, a.lightmap_uv + b.lightmap_uv, a.normal + b.normal};
}

// The quadratic Bezier patch of 3 x 3 control points `c` at (s, t): c[j * 3 + i], i along s, j along t.
BspVertex bezier(const std::array<BspVertex, 9>& c, float s, float t)
{
    const float bs[3] = {(1 - s) * (1 - s), 2 * s * (1 - s), s * s};
    const float bt[3] = {(1 - t) * (1 - t), 2 * t * (1 - t), t * t};
    BspVertex v{};
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
            v = v + (bs[i] * bt[j]) * c[size_t(j * 3 + i)];
    return v;
}

class BspReader
{
  public:
    BspReader(const std::vector<uint8_t>& bytes, std::string name) : bytes_(bytes), name_(std::move(name))
    {
        if (bytes_.size() < 8 + 8 * kLumpCount || std::memcmp(bytes_.data(), "IBSP", 4) != 0)
            throw error("not a Quake III BSP file (no IBSP header)");
        if (i32(&bytes_[4]) != 46)
            throw error("BSP version " + std::to_string(i32(&bytes_[4])) + ", not 46 (Quake III Arena)");
    }

    std::runtime_error error(const std::string& what) const
    {
        return std::runtime_error(name_ + ": " + what);
    }

    // The records of lump `lump`, each `record` bytes: their start and count.
    std::pair<const uint8_t*, size_t> lump(int lump, size_t record) const
    {
        const int64_t offset = i32(&bytes_[8 + 8 * size_t(lump)]),
                      length = i32(&bytes_[12 + 8 * size_t(lump)]);
        if (offset < 0 || length < 0 || uint64_t(offset) + uint64_t(length) > bytes_.size())
            throw error("lump " + std::to_string(lump) + " lies outside the file");
        if (length % int64_t(record))
            throw error("lump " + std::to_string(lump) + " is " + std::to_string(length) +
                        " bytes, not a whole number of " + std::to_string(record) + "-byte records");
        return {bytes_.data() + offset, size_t(length) / record};
    }

  private:
    const std::vector<uint8_t>& bytes_;
    std::string name_;
};

// Quake's z-up world in inches into glTF's y-up one: a rotation about x (determinant 1, so windings keep
// their sense), 64 inches to the unit.
glm::vec3 to_gltf(const glm::vec3& q)
{
    return glm::vec3(q.x, q.z, -q.y);
}
constexpr float kUnitsPerInch = 1.0f / 64.0f;

} // namespace

Q3Level convert_q3_level(const std::vector<uint8_t>& bsp, const std::string& name, int patch_level)
{
    if (patch_level < 1 || patch_level > 64)
        throw std::runtime_error(name + ": patch level " + std::to_string(patch_level) +
                                 " is not in [1, 64]");
    const BspReader r(bsp, name);
    const auto [textures, texture_count] = r.lump(kTextures, kTextureBytes);
    const auto [vertex_bytes, vertex_count] = r.lump(kVertexes, kVertexBytes);
    const auto [meshvert_bytes, meshvert_count] = r.lump(kMeshverts, 4);
    const auto [face_bytes, face_count] = r.lump(kFaces, kFaceBytes);
    const auto [lightmap_bytes, page_count] = r.lump(kLightmaps, kLightmapBytes);
    (void)textures;
    (void)lightmap_bytes;

    std::vector<BspVertex> vertices(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v)
    {
        const uint8_t* p = vertex_bytes + v * kVertexBytes;
        BspVertex& x = vertices[v];
        x.position = glm::vec3(f32(p), f32(p + 4), f32(p + 8));
        x.uv = glm::vec2(f32(p + 12), f32(p + 16));
        x.lightmap_uv = glm::vec2(f32(p + 20), f32(p + 24));
        x.normal = glm::vec3(f32(p + 28), f32(p + 32), f32(p + 36));
    }
    // Only the vertices of the faces kept must be finite: OpenArena's maps have NaN lightmap UVs on the
    // vertices of patches lit by vertex (oa_dm3's faces 76 and 77).
    auto check_finite = [&](int32_t first, int32_t count, const std::string& face)
    {
        for (int32_t v = first; v < first + count; ++v)
        {
            const BspVertex& x = vertices[size_t(v)];
            for (float c : {x.position.x, x.position.y, x.position.z, x.uv.x, x.uv.y, x.lightmap_uv.x,
                            x.lightmap_uv.y, x.normal.x, x.normal.y, x.normal.z})
                if (!std::isfinite(c))
                    throw r.error(face + "'s vertex " + std::to_string(v) + " has a non-finite value");
        }
    };

    Q3Level level;
    level.lightmap_pages = uint32_t(page_count);
    level.atlas_columns = std::max(1u, uint32_t(std::ceil(std::sqrt(double(page_count)))));
    level.atlas_rows = std::max(1u, (uint32_t(page_count) + level.atlas_columns - 1) / level.atlas_columns);
    io::Mesh& mesh = level.scene.mesh;

    // Appends a vertex: glTF's axes, the lightmap UV moved into its page's cell of the atlas grid. A normal
    // of no length (some compilers leave them so) takes `fallback`, the face's.
    auto emit = [&](const BspVertex& v, uint32_t page, const glm::vec3& fallback)
    {
        const glm::vec2 cell(float(page % level.atlas_columns), float(page / level.atlas_columns));
        const float length = glm::length(v.normal);
        mesh.positions.push_back(to_gltf(v.position) * kUnitsPerInch);
        mesh.normals.push_back(to_gltf(length > 1e-6f ? v.normal / length : fallback));
        mesh.uvs.push_back(v.uv);
        mesh.uvs1.push_back((cell + v.lightmap_uv) /
                            glm::vec2(float(level.atlas_columns), float(level.atlas_rows)));
        return uint32_t(mesh.positions.size() - 1);
    };

    for (size_t f = 0; f < face_count; ++f)
    {
        const uint8_t* p = face_bytes + f * kFaceBytes;
        const int32_t texture = i32(p), type = i32(p + 8), first_vertex = i32(p + 12), vertex_n = i32(p + 16);
        const int32_t first_meshvert = i32(p + 20), meshvert_n = i32(p + 24), page = i32(p + 28);
        const glm::vec3 face_normal(f32(p + 84), f32(p + 88), f32(p + 92));
        const int32_t patch_width = i32(p + 96), patch_height = i32(p + 100);
        const std::string face = "face " + std::to_string(f);
        if (texture < 0 || size_t(texture) >= texture_count)
            throw r.error(face + " names texture " + std::to_string(texture) + " of " +
                          std::to_string(texture_count));
        if (type == kBillboard)
        {
            ++level.billboards;
            continue;
        }
        if (type != kPolygon && type != kPatch && type != kMesh)
            throw r.error(face + " has the unknown type " + std::to_string(type));
        if (page < 0)
        {
            ++level.faces_without_lightmap;
            continue;
        }
        if (size_t(page) >= page_count)
            throw r.error(face + " names lightmap " + std::to_string(page) + " of " +
                          std::to_string(page_count));
        if (first_vertex < 0 || vertex_n < 0 || size_t(first_vertex) + size_t(vertex_n) > vertex_count)
            throw r.error(face + "'s vertices lie outside the vertex lump");
        check_finite(first_vertex, vertex_n, face);
        const glm::vec3 fallback =
            glm::length(face_normal) > 1e-6f ? glm::normalize(face_normal) : glm::vec3(0.0f, 0.0f, 1.0f);

        if (type == kPolygon || type == kMesh)
        {
            if (first_meshvert < 0 || meshvert_n < 0 || meshvert_n % 3 ||
                size_t(first_meshvert) + size_t(meshvert_n) > meshvert_count)
                throw r.error(face + "'s mesh vertices lie outside the mesh vertex lump");
            const uint32_t base = uint32_t(mesh.positions.size());
            for (int32_t v = 0; v < vertex_n; ++v)
                emit(vertices[size_t(first_vertex + v)], uint32_t(page), fallback);
            for (int32_t i = 0; i < meshvert_n; i += 3)
            {
                uint32_t corner[3];
                for (int k = 0; k < 3; ++k)
                {
                    const int32_t offset = i32(meshvert_bytes + 4 * size_t(first_meshvert + i + k));
                    if (offset < 0 || offset >= vertex_n)
                        throw r.error(face + " has the mesh vertex " + std::to_string(offset) + " of " +
                                      std::to_string(vertex_n));
                    corner[k] = base + uint32_t(offset);
                }
                // Quake's triangles run clockwise seen from the front; glTF's counter-clockwise.
                mesh.indices.insert(mesh.indices.end(), {corner[0], corner[2], corner[1]});
            }
            ++(type == kPolygon ? level.polygon_faces : level.mesh_faces);
            level.faces.resize(mesh.indices.size() / 3, uint32_t(f));
            continue;
        }

        // A patch: a grid of width x height control points (both odd, at least 3), cut into 3 x 3 patches
        // that share their border rows, each tessellated at patch_level.
        if (patch_width < 3 || patch_height < 3 || patch_width % 2 == 0 || patch_height % 2 == 0 ||
            int64_t(patch_width) * patch_height != vertex_n)
            throw r.error(face + " is a patch of " + std::to_string(patch_width) + " x " +
                          std::to_string(patch_height) + " control points for " + std::to_string(vertex_n) +
                          " vertices");
        const size_t first_index = mesh.indices.size();
        const uint32_t n = uint32_t(patch_level);
        for (int32_t py = 0; py + 2 < patch_height; py += 2)
            for (int32_t px = 0; px + 2 < patch_width; px += 2)
            {
                std::array<BspVertex, 9> control;
                for (int j = 0; j < 3; ++j)
                    for (int i = 0; i < 3; ++i)
                        control[size_t(j * 3 + i)] =
                            vertices[size_t(first_vertex + (py + j) * patch_width + px + i)];
                const uint32_t base = uint32_t(mesh.positions.size());
                for (uint32_t j = 0; j <= n; ++j)
                    for (uint32_t i = 0; i <= n; ++i)
                        emit(bezier(control, float(i) / float(n), float(j) / float(n)), uint32_t(page),
                             fallback);
                for (uint32_t j = 0; j < n; ++j)
                    for (uint32_t i = 0; i < n; ++i)
                    {
                        const uint32_t a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
                        mesh.indices.insert(mesh.indices.end(), {a, b, c, c, b, d});
                    }
                ++level.patches;
            }
        // A patch's grid has no winding of its own that the format fixes: turn the face's triangles to
        // agree with its vertex normals, as a whole (a single folded triangle does not decide it).
        double agreement = 0.0;
        for (size_t i = first_index; i < mesh.indices.size(); i += 3)
        {
            const glm::vec3 &a = mesh.positions[mesh.indices[i]], &b = mesh.positions[mesh.indices[i + 1]],
                            &c = mesh.positions[mesh.indices[i + 2]];
            agreement += glm::dot(glm::cross(b - a, c - a), mesh.normals[mesh.indices[i]] +
                                                                mesh.normals[mesh.indices[i + 1]] +
                                                                mesh.normals[mesh.indices[i + 2]]);
        }
        if (agreement < 0.0)
            for (size_t i = first_index; i < mesh.indices.size(); i += 3)
                std::swap(mesh.indices[i + 1], mesh.indices[i + 2]);
        ++level.patch_faces;
        level.faces.resize(mesh.indices.size() / 3, uint32_t(f));
    }
    if (mesh.indices.empty())
        throw r.error("no face with a lightmap (" + std::to_string(page_count) + " lightmaps, " +
                      std::to_string(face_count) + " faces)");

    io::Material grey;
    grey.name = "grey";
    grey.base_color_factor = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
    level.scene.materials = {grey};
    level.scene.primitives = {io::Primitive{0, uint32_t(mesh.indices.size()), 0}};
    return level;
}

Q3Level read_q3_level(const std::filesystem::path& pk3, const std::string& entry, int patch_level)
{
    return convert_q3_level(read_zip_entry(pk3, entry), pk3.string() + ":" + entry, patch_level);
}

} // namespace hemi::test
