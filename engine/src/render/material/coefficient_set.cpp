#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>

#include <glm/gtc/packing.hpp>
#include <glm/vec4.hpp>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::render
{
namespace
{
// Set 2 of `kind` with its one binding written, from the system's descriptor allocator.
gpu::DescriptorSet make_source_set(const MaterialSystem& system, CoefficientSourceKind kind,
                                   gpu::DescriptorWrite write)
{
    gpu::DescriptorSet set =
        system.descriptors().allocate(system.source_layout(kind), MaterialSystem::source_bindings(kind));
    write.binding = HEMI_SOURCE_BINDING_COEFFICIENTS;
    gpu::write_descriptors(system.device(), set, {&write, 1});
    return set;
}
} // namespace

VertexCoefficients::VertexCoefficients(const MaterialSystem& system, const gpu::Buffer& coefficients,
                                       uint64_t texels)
{
    const gpu::Device& device = system.device();
    if (texels == 0 || texels * 16 > coefficients.size())
        throw std::invalid_argument("hemi: " + std::to_string(texels) +
                                    " coefficient texels do not fit a buffer of " +
                                    std::to_string(coefficients.size()) + " bytes");
    if (texels > device.limits().maxTexelBufferElements)
        throw std::invalid_argument("hemi: " + std::to_string(texels) +
                                    " coefficient texels exceed the device's "
                                    "maxTexelBufferElements (" +
                                    std::to_string(device.limits().maxTexelBufferElements) + ")");
    view_ = gpu::create_buffer_view(device, coefficients, VK_FORMAT_R32G32B32A32_SFLOAT, 0, texels * 16);
    gpu::DescriptorWrite write;
    write.type = VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    write.texel_view = view_;
    set_ = make_source_set(system, CoefficientSourceKind::Vertex, write);
}

ProbeBuffer::ProbeBuffer(const MaterialSystem& system, uint32_t probes, uint32_t frames_in_flight)
    : probes_(probes), frames_(frames_in_flight)
{
    const gpu::Device& device = system.device();
    if (probes == 0 || frames_in_flight == 0)
        throw std::invalid_argument("hemi: a probe buffer needs at least one probe and one frame, got " +
                                    std::to_string(probes) + " and " + std::to_string(frames_in_flight));
    const VkDeviceSize bytes = VkDeviceSize(probes) * frames_in_flight * HEMI_BASIS_MAX_SIZE * 16;
    if (bytes > device.limits().maxStorageBufferRange)
        throw std::invalid_argument("hemi: " + std::to_string(probes) + " probes x " +
                                    std::to_string(frames_in_flight) + " frames (" + std::to_string(bytes) +
                                    " bytes) exceed the device's maxStorageBufferRange (" +
                                    std::to_string(device.limits().maxStorageBufferRange) + ")");
    buffer_ =
        gpu::create_buffer(device, {bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, gpu::MemoryUsage::Dynamic});
    device.set_name(VK_OBJECT_TYPE_BUFFER, buffer_.handle(), "hemi light probes");
    std::memset(buffer_.mapped(), 0, bytes);
    gpu::DescriptorWrite write;
    write.type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.buffer = {buffer_, 0, VK_WHOLE_SIZE};
    set_ = make_source_set(system, CoefficientSourceKind::Uniform, write);
}

uint32_t ProbeBuffer::offset(uint32_t frame, uint32_t probe) const
{
    if (frame >= frames_ || probe >= probes_)
        throw std::invalid_argument("hemi: probe " + std::to_string(probe) + " of frame slot " +
                                    std::to_string(frame) + " in a buffer of " + std::to_string(probes_) +
                                    " probes and " + std::to_string(frames_) + " frame(s)");
    return (frame * probes_ + probe) * HEMI_BASIS_MAX_SIZE;
}

void ProbeBuffer::pack(uint32_t frame, uint32_t probe, std::span<const glm::vec3> coefficients,
                       glm::vec4* out) const
{
    (void)offset(frame, probe);
    if (coefficients.size() > HEMI_BASIS_MAX_SIZE)
        throw std::invalid_argument("hemi: a probe holds at most " + std::to_string(HEMI_BASIS_MAX_SIZE) +
                                    " coefficients, got " + std::to_string(coefficients.size()));
    for (size_t i = 0; i < HEMI_BASIS_MAX_SIZE; ++i)
    {
        const glm::vec3 c = i < coefficients.size() ? coefficients[i] : glm::vec3(0.0f);
        if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
            throw std::invalid_argument("hemi: probe " + std::to_string(probe) + "'s coefficient " +
                                        std::to_string(i) + " is not finite");
        out[i] = glm::vec4(c, 0.0f);
    }
}

void ProbeBuffer::write(uint32_t frame, uint32_t probe, std::span<const glm::vec3> coefficients)
{
    glm::vec4 packed[HEMI_BASIS_MAX_SIZE];
    pack(frame, probe, coefficients, packed);
    std::memcpy(static_cast<glm::vec4*>(buffer_.mapped()) + offset(frame, probe), packed, sizeof packed);
}

void ProbeBuffer::record_update(VkCommandBuffer cmd, uint32_t frame, uint32_t probe,
                                std::span<const glm::vec3> coefficients) const
{
    glm::vec4 packed[HEMI_BASIS_MAX_SIZE];
    pack(frame, probe, coefficients, packed);
    record_uniform_update(cmd, buffer_, packed, sizeof packed, VkDeviceSize(offset(frame, probe)) * 16,
                          VK_ACCESS_SHADER_READ_BIT);
}

TexelCoefficients::TexelCoefficients(const MaterialSystem& system, uint32_t width, uint32_t height,
                                     uint32_t k, std::span<const float> rgb, gpu::UploadBatch& upload,
                                     bool full_precision)
    : k_(k)
{
    const gpu::Device& device = system.device();
    if (k == 0 || k > HEMI_BASIS_MAX_SIZE)
        throw std::invalid_argument("hemi: coefficient maps need 1 to " +
                                    std::to_string(HEMI_BASIS_MAX_SIZE) + " layers, got " +
                                    std::to_string(k));
    const size_t texels = size_t(width) * height * k;
    if (width == 0 || height == 0 || rgb.size() != texels * 3)
        throw std::invalid_argument("hemi: coefficient maps of " + std::to_string(width) + "x" +
                                    std::to_string(height) + "x" + std::to_string(k) + " need " +
                                    std::to_string(texels * 3) + " floats, got " +
                                    std::to_string(rgb.size()));
    for (size_t i = 0; i < rgb.size(); ++i)
        if (!std::isfinite(rgb[i]) || (!full_precision && std::abs(rgb[i]) > 65504.0f))
            throw std::invalid_argument(
                "hemi: coefficient map value " + std::to_string(i) +
                (std::isfinite(rgb[i]) ? " exceeds the half-float range" : " is not finite"));
    // Packed (hemi_lightmap_coefficients): float f = 3 k + c of texel t is channel f % 4 of layer f / 4.
    const uint32_t layers = packed_layers(k);
    const size_t plane = size_t(width) * height;
    const VkFormat format = full_precision ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R16G16B16A16_SFLOAT;
    maps_ = gpu::create_image(device, {width, height, format, VK_IMAGE_USAGE_SAMPLED_BIT, 1, layers, true});
    auto pack = [&](auto convert, auto& rgba)
    {
        rgba.assign(plane * layers * 4, convert(0.0f));
        for (uint32_t c = 0; c < k; ++c)
            for (size_t t = 0; t < plane; ++t)
                for (uint32_t ch = 0; ch < 3; ++ch)
                {
                    const uint32_t f = 3 * c + ch;
                    rgba[((f / 4) * plane + t) * 4 + f % 4] = convert(rgb[(c * plane + t) * 3 + ch]);
                }
        upload.image(maps_, rgba.data(), rgba.size() * sizeof(rgba[0]));
    };
    if (full_precision)
    {
        std::vector<float> rgba;
        pack([](float v) { return v; }, rgba);
    }
    else
    {
        std::vector<uint16_t> rgba;
        pack([](float v) { return uint16_t(glm::packHalf1x16(v)); }, rgba);
    }
    // Bilinear, clamped: a lightmap's charts are padded, and nothing wraps across the atlas's border.
    sampler_ = gpu::create_sampler(device, {VK_FILTER_LINEAR, VK_SAMPLER_MIPMAP_MODE_NEAREST,
                                            VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, 0.0f});
    gpu::DescriptorWrite write;
    write.type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    write.image = {sampler_, maps_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    set_ = make_source_set(system, CoefficientSourceKind::Texel, write);
}

} // namespace hemi::render
