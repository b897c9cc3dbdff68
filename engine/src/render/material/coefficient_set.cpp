#include <hemi/io/half_scale.h>
#include <hemi/render/material/coefficient_set.h>
#include <hemi/render/material/frame_set.h>
#include <hemi/shared/bases.h>

#include <glm/gtc/packing.hpp>
#include <glm/vec4.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace hemi::render
{
namespace
{
// Set 2 of `kind` with its bindings written (`writes`, the first to HEMI_SOURCE_BINDING_COEFFICIENTS
// unless it names another), from the system's descriptor allocator.
gpu::DescriptorSet make_source_set(const MaterialSystem& system, CoefficientSourceKind kind,
                                   gpu::DescriptorWrite write)
{
    gpu::DescriptorSet set =
        system.descriptors().allocate(system.source_layout(kind), MaterialSystem::source_bindings(kind));
    write.binding = HEMI_SOURCE_BINDING_COEFFICIENTS;
    gpu::write_descriptors(system.device(), set, {&write, 1});
    return set;
}

void check_k(uint32_t k)
{
    if (k == 0 || k > HEMI_BASIS_MAX_SIZE)
        throw std::invalid_argument("hemi: coefficient maps need 1 to " +
                                    std::to_string(HEMI_BASIS_MAX_SIZE) + " layers, got " +
                                    std::to_string(k));
}

void check_values(std::span<const float> values)
{
    for (size_t i = 0; i < values.size(); ++i)
        if (!std::isfinite(values[i]))
            throw std::invalid_argument("hemi: coefficient map value " + std::to_string(i) +
                                        " is not finite");
}
} // namespace

VertexCoefficients::VertexCoefficients(const MaterialSystem& system, const gpu::BufferRange& coefficients,
                                       uint64_t texels)
{
    const gpu::Device& device = system.device();
    if (texels == 0 || texels * 16 > coefficients.size)
        throw std::invalid_argument("hemi: " + std::to_string(texels) +
                                    " coefficient texels do not fit a buffer range of " +
                                    std::to_string(coefficients.size) + " bytes");
    if (texels > device.limits().maxTexelBufferElements)
        throw std::invalid_argument("hemi: " + std::to_string(texels) +
                                    " coefficient texels exceed the device's "
                                    "maxTexelBufferElements (" +
                                    std::to_string(device.limits().maxTexelBufferElements) + ")");
    view_ = gpu::create_buffer_view(device, coefficients.buffer, VK_FORMAT_R32G32B32A32_SFLOAT,
                                    coefficients.offset, texels * 16);
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
                       const Occlusion& occlusion, glm::vec4* out) const
{
    for (float o : occlusion)
        if (!(o >= 0.0f && o <= 1.0f))
            throw std::invalid_argument("hemi: probe " + std::to_string(probe) +
                                        "'s occlusion is outside [0, 1]");
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
        out[i] = glm::vec4(c, i < 4 ? occlusion[i] : 0.0f);
    }
}

void ProbeBuffer::write(uint32_t frame, uint32_t probe, std::span<const glm::vec3> coefficients,
                        const Occlusion& occlusion)
{
    glm::vec4 packed[HEMI_BASIS_MAX_SIZE];
    pack(frame, probe, coefficients, occlusion, packed);
    std::memcpy(static_cast<glm::vec4*>(buffer_.mapped()) + offset(frame, probe), packed, sizeof packed);
}

void ProbeBuffer::record_update(VkCommandBuffer cmd, uint32_t frame, uint32_t probe,
                                std::span<const glm::vec3> coefficients, const Occlusion& occlusion) const
{
    glm::vec4 packed[HEMI_BASIS_MAX_SIZE];
    pack(frame, probe, coefficients, occlusion, packed);
    record_uniform_update(cmd, buffer_, packed, sizeof packed, VkDeviceSize(offset(frame, probe)) * 16,
                          VK_ACCESS_SHADER_READ_BIT);
}

TexelCoefficients::TexelCoefficients(const MaterialSystem& system, uint32_t width, uint32_t height,
                                     uint32_t k, std::span<const float> rgb, gpu::UploadBatch& upload,
                                     bool full_precision)
    : TexelCoefficients(
          system,
          [&]
          {
              check_k(k);
              const size_t texels = size_t(width) * height * k;
              if (width == 0 || height == 0 || rgb.size() != texels * 3)
                  throw std::invalid_argument("hemi: coefficient maps of " + std::to_string(width) + "x" +
                                              std::to_string(height) + "x" + std::to_string(k) + " need " +
                                              std::to_string(texels * 3) + " floats, got " +
                                              std::to_string(rgb.size()));
              check_values(rgb);
              return io::BlockMaps::from_dense(width, height, k, rgb);
          }(),
          upload, full_precision)
{
}

TexelCoefficients::TexelCoefficients(const MaterialSystem& system, const io::BlockMaps& maps,
                                     gpu::UploadBatch& upload, bool full_precision,
                                     const io::BlockMaps* shadowmask)
    : has_shadowmask_(shadowmask != nullptr), k_(maps.k)
{
    const gpu::Device& device = system.device();
    check_k(maps.k);
    const io::BlockGrid& grid = maps.grid;
    const uint32_t width = grid.width(), height = grid.height(), k = maps.k;
    if (width == 0 || height == 0 || maps.values.size() != grid.slots() * k * 3)
        throw std::invalid_argument("hemi: coefficient maps of " + std::to_string(width) + "x" +
                                    std::to_string(height) + " hold " + std::to_string(maps.values.size()) +
                                    " values for " + std::to_string(grid.slots()) + " texels of " +
                                    std::to_string(k) + " coefficients");
    check_values(maps.values);
    if (shadowmask)
    {
        if (shadowmask->k != 4 || shadowmask->width() != width || shadowmask->height() != height ||
            shadowmask->values.size() != shadowmask->grid.slots() * 4 * 3)
            throw std::invalid_argument("hemi: a shadowmask must be 4 maps of the lightmap's " +
                                        std::to_string(width) + "x" + std::to_string(height) + " atlas");
        for (float v : shadowmask->values)
            if (!(v >= 0.0f && v <= 1.0f))
                throw std::invalid_argument("hemi: a shadowmask value is outside [0, 1]");
    }

    // The pages whose slot (the page and its border) holds a texel of a kept block, numbered row after row:
    // the page table's entries (slot + 1). A page without a kept block of its own but beside one is stored
    // too: a lookup within half a texel of its edge reads the neighbour's texels.
    constexpr uint32_t P = HEMI_LIGHTMAP_PAGE, S = HEMI_LIGHTMAP_SLOT, E = io::BlockGrid::kSize;
    const uint32_t pages_x = (width + P - 1) / P, pages_y = (height + P - 1) / P;
    const uint32_t table_width = std::max(3u, pages_x);
    std::vector<uint32_t> table(size_t(table_width) * (pages_y + 1), 0);
    // Pages whose range widened by a texel on each side meets texels [t0, t0 + E).
    auto pages_meeting = [&](uint32_t t0, uint32_t count)
    { return std::pair<uint32_t, uint32_t>(t0 == 0 ? 0 : (t0 - 1) / P, std::min((t0 + E) / P, count - 1)); };
    for (const io::BlockGrid* g : {&grid, shadowmask ? &shadowmask->grid : nullptr})
        for (uint32_t b : g ? g->blocks() : std::vector<uint32_t>{})
        {
            const auto [x0, x1] = pages_meeting((b % g->blocks_x()) * E, pages_x);
            const auto [y0, y1] = pages_meeting((b / g->blocks_x()) * E, pages_y);
            for (uint32_t py = y0; py <= y1; ++py)
                for (uint32_t px = x0; px <= x1; ++px)
                    table[size_t(py) * table_width + px] = 1;
        }
    std::vector<uint32_t> stored; // page index (y * table_width + x) of each slot
    for (uint32_t p = 0; p < table_width * pages_y; ++p)
        if (table[p])
        {
            stored.push_back(p);
            table[p] = uint32_t(stored.size());
        }
    table[size_t(pages_y) * table_width] = width;
    table[size_t(pages_y) * table_width + 1] = height;
    // Half floats hold light of any magnitude with a power-of-two scale (io/half_scale.h), which the lookup
    // multiplies back: its float's bits in texel 2 of the last row.
    const int exponent = full_precision ? 0 : io::half_scale_exponent(io::largest_magnitude(maps.values));
    scale_ = std::ldexp(1.0f, exponent);
    std::memcpy(&table[size_t(pages_y) * table_width + 2], &scale_, 4);
    stored_pages_ = uint32_t(stored.size());

    // Slots row after row in one image no larger than the device's largest.
    const uint32_t largest = device.limits().maxImageDimension2D;
    const uint32_t most_per_row = std::max(1u, largest / S);
    const uint32_t per_row = std::clamp<uint32_t>(stored_pages_, 1, most_per_row);
    const uint32_t rows = std::max(1u, (stored_pages_ + per_row - 1) / per_row);
    if (uint64_t(rows) * S > largest)
        throw std::invalid_argument(
            "hemi: a lightmap of " + std::to_string(width) + "x" + std::to_string(height) + " stores " +
            std::to_string(stored_pages_) + " pages of " + std::to_string(P) + "^2 texels; one image of " +
            std::to_string(largest) + "^2 holds " + std::to_string(uint64_t(most_per_row) * most_per_row));
    if (table_width > largest || pages_y + 1 > largest)
        throw std::invalid_argument("hemi: a lightmap of " + std::to_string(width) + "x" +
                                    std::to_string(height) + " needs a page table larger than the device's " +
                                    std::to_string(largest) + "^2 images");
    const uint32_t pw = per_row * S, ph = rows * S, layers = packed_layers(k);
    const size_t plane = size_t(pw) * ph;

    // Every texel of every stored slot (its border included), with the atlas texel it holds (the edge
    // texels at the atlas's edge): visit(at, x, y), `at` the texel's index in one layer of the slots' image.
    auto for_each_slot_texel = [&](auto visit)
    {
        for (size_t s = 0; s < stored.size(); ++s)
        {
            const uint32_t px = uint32_t(stored[s] % table_width), py = uint32_t(stored[s] / table_width);
            const size_t ox = (s % per_row) * S, oy = (s / per_row) * S;
            for (uint32_t gy = 0; gy < S; ++gy)
            {
                const int64_t y = std::clamp<int64_t>(int64_t(py) * P + gy - 1, 0, height - 1);
                for (uint32_t gx = 0; gx < S; ++gx)
                {
                    const int64_t x = std::clamp<int64_t>(int64_t(px) * P + gx - 1, 0, width - 1);
                    visit((oy + gy) * pw + ox + gx, x, y);
                }
            }
        }
    };
    // Packed (hemi_lightmap_coefficients): float f = 3 k + c of a texel is channel f % 4 of layer f / 4.
    auto fill = [&](auto convert, auto& rgba)
    {
        rgba.assign(plane * layers * 4, convert(0.0f));
        for_each_slot_texel(
            [&](size_t at, int64_t x, int64_t y)
            {
                const int64_t slot = grid.slot(x, y);
                if (slot < 0)
                    return;
                const size_t first = (size_t(slot) / io::BlockGrid::kTexels * k) * io::BlockGrid::kTexels +
                                     size_t(slot) % io::BlockGrid::kTexels;
                for (uint32_t c = 0; c < k; ++c)
                    for (uint32_t ch = 0; ch < 3; ++ch)
                    {
                        const uint32_t f = 3 * c + ch;
                        rgba[((f / 4) * plane + at) * 4 + f % 4] =
                            convert(maps.values[(first + size_t(c) * io::BlockGrid::kTexels) * 3 + ch]);
                    }
            });
    };
    const VkFormat format = full_precision ? VK_FORMAT_R32G32B32A32_SFLOAT : VK_FORMAT_R16G16B16A16_SFLOAT;
    pages_ = gpu::create_image(device, {pw, ph, format, VK_IMAGE_USAGE_SAMPLED_BIT, 1, layers, true});
    if (full_precision)
    {
        std::vector<float> rgba;
        fill([](float v) { return v; }, rgba);
        upload.image(pages_, rgba.data(), rgba.size() * sizeof(rgba[0]));
    }
    else
    {
        std::vector<uint16_t> rgba;
        fill([&](float v) { return uint16_t(glm::packHalf1x16(std::ldexp(v, -exponent))); }, rgba);
        upload.image(pages_, rgba.data(), rgba.size() * sizeof(rgba[0]));
    }
    // The shadowmask's channels in the same slots, as RGBA8 (the asset's 8 bits); one white texel without
    // one.
    if (shadowmask)
    {
        // White where the mask stores no texel (a coefficient map's block the mask lacks): unshadowed.
        std::vector<uint8_t> rgba(plane * 4, 255);
        for_each_slot_texel(
            [&](size_t at, int64_t x, int64_t y)
            {
                const int64_t slot = shadowmask->grid.slot(x, y);
                if (slot < 0)
                    return;
                for (uint32_t c = 0; c < 4; ++c)
                    rgba[at * 4 + c] =
                        uint8_t(std::lround(shadowmask->values[shadowmask->index(c, size_t(slot))] * 255.0f));
            });
        shadowmask_ = gpu::create_image(
            device, {pw, ph, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT, 1, 1, true});
        upload.image(shadowmask_, rgba.data(), rgba.size());
    }
    else
    {
        const uint8_t white[4] = {255, 255, 255, 255};
        shadowmask_ = gpu::create_image(
            device, {1, 1, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_USAGE_SAMPLED_BIT, 1, 1, true});
        upload.image(shadowmask_, white, 4);
    }
    page_table_ = gpu::create_image(device, {table_width, pages_y + 1, VK_FORMAT_R32_UINT});
    upload.image(page_table_, table.data(), table.size() * sizeof(uint32_t));
    // Bilinear, clamped: a lightmap's charts are padded, and every slot has its border.
    sampler_ = gpu::create_sampler(device, {VK_FILTER_LINEAR, VK_SAMPLER_MIPMAP_MODE_NEAREST,
                                            VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, 0.0f});
    table_sampler_ = gpu::create_sampler(device, {VK_FILTER_NEAREST, VK_SAMPLER_MIPMAP_MODE_NEAREST,
                                                  VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE, 0.0f});
    set_ = system.descriptors().allocate(system.source_layout(CoefficientSourceKind::Texel),
                                         MaterialSystem::source_bindings(CoefficientSourceKind::Texel));
    gpu::DescriptorWrite writes[3];
    writes[0].binding = HEMI_SOURCE_BINDING_COEFFICIENTS;
    writes[0].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[0].image = {sampler_, pages_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    writes[1].binding = HEMI_SOURCE_BINDING_PAGE_TABLE;
    writes[1].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[1].image = {table_sampler_, page_table_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    writes[2].binding = HEMI_SOURCE_BINDING_SHADOWMASK;
    writes[2].type = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[2].image = {sampler_, shadowmask_.view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    gpu::write_descriptors(device, set_, writes);
}

} // namespace hemi::render
