#include <hemi/bake/embree_scene.h>

#include <embree3/rtcore.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::bake
{

struct EmbreeScene::Impl
{
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    // Embree's own copies (the geometry's buffers, alive as long as the scene): read by geometric_normal().
    const float* positions = nullptr;
    const uint32_t* indices = nullptr;
    std::vector<glm::vec3> normals; // per triangle, cross(p1 - p0, p2 - p0): geometric_normal()
    std::mutex error_mutex;         // Embree may report from its worker threads
    std::string error;
    bool out_of_memory = false; // Embree said RTC_ERROR_OUT_OF_MEMORY: thrown as std::bad_alloc

    ~Impl()
    {
        if (scene)
            rtcReleaseScene(scene);
        if (device)
            rtcReleaseDevice(device);
    }

    // The message for a failure in `what`, with Embree's last error when it gave one.
    std::string failure(const std::string& what)
    {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (out_of_memory)
            throw std::bad_alloc();
        return "hemi: Embree failed " + what + (error.empty() ? "" : ": " + error);
    }
};

namespace
{

void check_mesh(const io::Mesh& mesh)
{
    const size_t n = mesh.vertex_count();
    if (n == 0 || mesh.indices.empty() || mesh.indices.size() % 3)
        throw std::invalid_argument("hemi: EmbreeScene needs vertices and a non-empty triangle list (" +
                                    std::to_string(mesh.indices.size()) + " indices)");
    for (uint32_t i : mesh.indices)
        if (i >= n)
            throw std::invalid_argument("hemi: EmbreeScene: mesh index " + std::to_string(i) +
                                        " is out of range (" + std::to_string(n) + " vertices)");
    for (const glm::vec3& p : mesh.positions)
    {
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw std::invalid_argument("hemi: EmbreeScene: the mesh has a non-finite position");
        // Embree's rays are valid within +-1.8e18, and float positions that far out are kilometres apart;
        // a level in metres (or centimetres) is far inside +-1e9.
        if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > 1e9f)
            throw std::invalid_argument("hemi: the mesh has a position beyond +-1e9 units of the origin (" +
                                        std::to_string(p.x) + ", " + std::to_string(p.y) + ", " +
                                        std::to_string(p.z) + "): too far out for ray tracing in floats");
    }
}

void init_ray(RTCRay& ray, const glm::vec3& origin, const glm::vec3& direction, float t_near, float t_far)
{
    ray.org_x = origin.x;
    ray.org_y = origin.y;
    ray.org_z = origin.z;
    ray.dir_x = direction.x;
    ray.dir_y = direction.y;
    ray.dir_z = direction.z;
    ray.tnear = t_near;
    ray.tfar = t_far;
    ray.mask = 0xffffffffu;
}

} // namespace

EmbreeScene::EmbreeScene(const io::Mesh& mesh) : impl_(std::make_unique<Impl>())
{
    check_mesh(mesh);
    Impl& s = *impl_;
    // On a throw below, impl_'s destructor releases whatever was created.
    s.device = rtcNewDevice(nullptr);
    if (!s.device && rtcGetDeviceError(nullptr) == RTC_ERROR_OUT_OF_MEMORY)
        throw std::bad_alloc(); // as any other allocation that fails: the tools say where and how much
    if (!s.device)
        throw std::runtime_error("hemi: Embree device creation failed (error " +
                                 std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
    rtcSetDeviceErrorFunction(
        s.device,
        [](void* user, RTCError code, const char* message)
        {
            auto* self = static_cast<Impl*>(user);
            std::lock_guard<std::mutex> lock(self->error_mutex);
            self->error = message ? message : "unknown Embree error";
            self->out_of_memory = self->out_of_memory || code == RTC_ERROR_OUT_OF_MEMORY;
        },
        &s);
    s.scene = rtcNewScene(s.device);
    rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geometry = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertex_count()));
    auto* ib = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), mesh.indices.size() / 3));
    if (!vb || !ib)
    {
        rtcReleaseGeometry(geometry);
        throw std::runtime_error(s.failure("allocating the geometry"));
    }
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
        for (int c = 0; c < 3; ++c)
            vb[v * 3 + c] = mesh.positions[v][c];
    std::copy(mesh.indices.begin(), mesh.indices.end(), ib);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(s.scene, geometry);
    rtcReleaseGeometry(geometry); // the scene keeps it, and with it the buffers
    rtcCommitScene(s.scene);
    bool failed;
    {
        std::lock_guard<std::mutex> lock(s.error_mutex);
        failed = !s.error.empty();
    }
    if (failed)
    {
        // A scene whose build failed (out of memory in Embree's TBB tasks) may call std::terminate when it is
        // released (Embree 3.13 waits on the build's broken task group): it and its device are left to the
        // process's exit, which the error is on its way to.
        const std::string message = [&]
        {
            const std::lock_guard<std::mutex> lock(s.error_mutex);
            return s.out_of_memory ? std::string() : "hemi: Embree failed building the scene: " + s.error;
        }();
        s.scene = nullptr;
        s.device = nullptr;
        if (message.empty())
            throw std::bad_alloc();
        throw std::runtime_error(message);
    }
    s.positions = vb;
    s.indices = ib;
    triangle_count_ = uint32_t(mesh.indices.size() / 3);
    s.normals.resize(triangle_count_);
    for (uint32_t t = 0; t < triangle_count_; ++t)
    {
        const uint32_t* tri = &ib[size_t(t) * 3];
        const glm::vec3 p0(vb[size_t(tri[0]) * 3], vb[size_t(tri[0]) * 3 + 1], vb[size_t(tri[0]) * 3 + 2]),
            p1(vb[size_t(tri[1]) * 3], vb[size_t(tri[1]) * 3 + 1], vb[size_t(tri[1]) * 3 + 2]),
            p2(vb[size_t(tri[2]) * 3], vb[size_t(tri[2]) * 3 + 1], vb[size_t(tri[2]) * 3 + 2]);
        s.normals[t] = glm::cross(p1 - p0, p2 - p0);
    }

    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const glm::vec3& p : mesh.positions)
    {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    diagonal_ = glm::length(hi - lo);
}

EmbreeScene::~EmbreeScene() = default;
EmbreeScene::EmbreeScene(EmbreeScene&&) noexcept = default;
EmbreeScene& EmbreeScene::operator=(EmbreeScene&&) noexcept = default;

std::optional<RayHit> EmbreeScene::intersect(const glm::vec3& origin, const glm::vec3& direction,
                                             float t_near, float t_far) const
{
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh{};
    init_ray(rh.ray, origin, direction, t_near, t_far);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return std::nullopt;
    return RayHit{rh.hit.primID, rh.hit.u, rh.hit.v, rh.ray.tfar};
}

bool EmbreeScene::occluded(const glm::vec3& origin, const glm::vec3& direction, float t_near,
                           float t_far) const
{
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray{};
    init_ray(ray, origin, direction, t_near, t_far);
    rtcOccluded1(impl_->scene, &context, &ray);
    return ray.tfar == -INFINITY; // Embree's mark of an occluded ray
}

namespace
{

constexpr size_t kPacket = 16;

// Rays [first, first + count) of `rays` into a packet's lanes; the lanes past `count` are off.
template <class Packet>
void fill_packet(Packet& ray, int (&valid)[kPacket], std::span<const Ray> rays, size_t first, size_t count)
{
    for (size_t j = 0; j < kPacket; ++j)
    {
        valid[j] = j < count ? -1 : 0;
        const Ray& r = rays[first + std::min(j, count - 1)];
        ray.org_x[j] = r.origin.x;
        ray.org_y[j] = r.origin.y;
        ray.org_z[j] = r.origin.z;
        ray.dir_x[j] = r.direction.x;
        ray.dir_y[j] = r.direction.y;
        ray.dir_z[j] = r.direction.z;
        ray.tnear[j] = r.t_near;
        ray.tfar[j] = r.t_far;
        ray.mask[j] = 0xffffffffu;
        ray.time[j] = 0.0f;
        ray.flags[j] = 0;
    }
}

// The packets of a batch of `rays` rays whose answers go to `room` places: trace(context, first, count) for
// each run of up to 16. Throws std::invalid_argument when room is not rays.
template <class Trace> void for_each_packet(const char* query, size_t rays, size_t room, Trace&& trace)
{
    if (room != rays)
        throw std::invalid_argument(std::string("hemi: EmbreeScene::") + query + ": " + std::to_string(rays) +
                                    " rays but room for " + std::to_string(room) + " answers");
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (size_t first = 0; first < rays; first += kPacket)
        trace(context, first, std::min(kPacket, rays - first));
}

} // namespace

void EmbreeScene::intersect(std::span<const Ray> rays, std::span<std::optional<RayHit>> hits) const
{
    for_each_packet("intersect", rays.size(), hits.size(),
                    [&](RTCIntersectContext& context, size_t first, size_t count)
                    {
                        alignas(64) int valid[kPacket];
                        alignas(64) RTCRayHit16 packet;
                        fill_packet(packet.ray, valid, rays, first, count);
                        for (size_t j = 0; j < kPacket; ++j)
                        {
                            packet.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
                            packet.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
                        }
                        rtcIntersect16(valid, impl_->scene, &context, &packet);
                        for (size_t j = 0; j < count; ++j)
                            if (packet.hit.geomID[j] == RTC_INVALID_GEOMETRY_ID)
                                hits[first + j].reset();
                            else
                                hits[first + j] = RayHit{packet.hit.primID[j], packet.hit.u[j],
                                                         packet.hit.v[j], packet.ray.tfar[j]};
                    });
}

void EmbreeScene::occluded(std::span<const Ray> rays, std::span<uint8_t> blocked) const
{
    for_each_packet("occluded", rays.size(), blocked.size(),
                    [&](RTCIntersectContext& context, size_t first, size_t count)
                    {
                        alignas(64) int valid[kPacket];
                        alignas(64) RTCRay16 packet;
                        fill_packet(packet, valid, rays, first, count);
                        rtcOccluded16(valid, impl_->scene, &context, &packet);
                        for (size_t j = 0; j < count; ++j)
                            blocked[first + j] = packet.tfar[j] == -INFINITY;
                    });
}

glm::vec3 EmbreeScene::geometric_normal(uint32_t primitive) const
{
    return impl_->normals[primitive];
}

int EmbreeScene::embree_version()
{
    return RTC_VERSION;
}

} // namespace hemi::bake
