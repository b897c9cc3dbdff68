// Links hemi from its installed package, runs the transfer pass on the device and the host, and checks
// that both give T * l for a matrix whose product is known.
#ifdef HEMI_CONSUMER_BAKER
#include <hemi/bake/normal_map.h>
#endif
#include <hemi/gpu/device.h>
#include <hemi/render/transfer.h>

#include <glm/vec4.hpp>

#include <cstdio>
#include <vector>

int main()
{
    const uint32_t n = 100, k = 4, l = 9;
    std::vector<float> t(size_t(n) * k * l, 0.0f);
    for (uint32_t v = 0; v < n; ++v)
        for (uint32_t i = 0; i < k; ++i)
            t[(size_t(v) * k + i) * l + i] = float(v); // T_v = v * [I_4 | 0]
    hemi::render::TransferMatrices m(n, k, l, t);
    std::vector<glm::vec3> light(l, glm::vec3(1.0f, 2.0f, 3.0f));
    std::vector<float> host(size_t(n) * k * 4);
    hemi::render::transfer_multiply_host(m, light, host);

    // hemi exports no GLM settings: an engine's colour swizzles still compile against its headers.
    const glm::vec4 colour(0.25f, 0.5f, 0.75f, 1.0f);
    if (colour.r != 0.25f || colour.b != 0.75f)
        return 1;

    hemi::gpu::Device device;
    hemi::render::TransferPass pass(device, m);
    pass.run(light);
    std::vector<float> gpu = pass.read_coefficients();
    for (uint32_t v = 0; v < n; ++v)
        for (uint32_t i = 0; i < k; ++i)
            for (int c = 0; c < 3; ++c)
            {
                float want = float(v) * float(c + 1);
                if (gpu[(v * k + i) * 4 + c] != want || host[(v * k + i) * 4 + c] != want)
                {
                    std::fprintf(stderr, "consumer: wrong coefficient at vertex %u\n", v);
                    return 1;
                }
            }
    std::printf("consumer: hemi package OK on %.*s\n", int(device.name().size()), device.name().data());
    return 0;
}
