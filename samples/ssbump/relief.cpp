#include "relief.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hemi::samples
{
namespace
{

// A hash of integer lattice points in [0, 1).
float hash01(int64_t x, int64_t y, uint32_t salt)
{
    uint64_t h =
        uint64_t(x) * 0x9E3779B97F4A7C15ull ^ (uint64_t(y) + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
    h ^= salt * 0x165667B19E3779F9ull;
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 29;
    return float(h >> 40) / float(1 << 24);
}

// Smooth value noise on a lattice of `period` cells, wrapping at `period`.
float value_noise(float x, float y, int period, uint32_t salt)
{
    const int64_t x0 = int64_t(std::floor(x)), y0 = int64_t(std::floor(y));
    const float fx = x - float(x0), fy = y - float(y0);
    auto v = [&](int64_t i, int64_t j)
    { return hash01(((i % period) + period) % period, ((j % period) + period) % period, salt); };
    const float sx = fx * fx * (3.0f - 2.0f * fx), sy = fy * fy * (3.0f - 2.0f * fy);
    const float a = v(x0, y0) + sx * (v(x0 + 1, y0) - v(x0, y0));
    const float b = v(x0, y0 + 1) + sx * (v(x0 + 1, y0 + 1) - v(x0, y0 + 1));
    return a + sy * (b - a);
}

} // namespace

bake::HeightField make_relief(uint32_t size)
{
    if (size < 64 || size % 64 != 0)
        throw std::invalid_argument("make_relief: size " + std::to_string(size) + " is not a multiple of 64");
    const int n = int(size);
    const int brick_w = n / 8, brick_h = n / 16;
    const float mortar = float(n) / 100.0f; // half the joint's width
    const float bevel = float(n) / 160.0f;
    bake::HeightField f{size, size, std::vector<float>(size_t(size) * size)};
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
        {
            const int row = y / brick_h;
            const int shifted = (x + (row % 2) * brick_w / 2) % n; // running bond
            const int col = shifted / brick_w;
            // Distance to the nearest joint, in texels (a joint runs along every brick edge).
            const float lx = float(shifted % brick_w) + 0.5f, ly = float(y % brick_h) + 0.5f;
            const float edge = std::min(std::min(lx, float(brick_w) - lx), std::min(ly, float(brick_h) - ly));
            float h;
            if (edge < mortar)
                h = 0.05f * value_noise(float(x) / 4.0f, float(y) / 4.0f, n / 4, 7); // the joint's floor
            else
            {
                const float t = std::min(1.0f, (edge - mortar) / bevel);
                h = 0.75f * std::sqrt(t * (2.0f - t)); // rounded bevel up to the face
                h += 0.04f * (value_noise(float(x) / 16.0f, float(y) / 16.0f, n / 16, 3) - 0.5f);
                const float r = hash01(col, row, 11);
                const float cx = float(brick_w) * 0.5f, cy = float(brick_h) * 0.5f;
                const float dx = lx - cx, dy = ly - cy;
                if (r < 0.3f)
                {
                    // Four rivets near the corners.
                    const float rr = float(brick_h) * 0.12f;
                    for (float sx : {-1.0f, 1.0f})
                        for (float sy : {-1.0f, 1.0f})
                        {
                            const float ex = dx - sx * (cx - 2.2f * rr), ey = dy - sy * (cy - 2.2f * rr);
                            const float d2 = (ex * ex + ey * ey) / (rr * rr);
                            if (d2 < 1.0f)
                                h += 0.2f * std::sqrt(1.0f - d2);
                        }
                }
                else if (r < 0.55f)
                {
                    // A crater: a bowl with a raised rim, off centre.
                    const float ox = (hash01(col, row, 13) - 0.5f) * float(brick_w) * 0.4f;
                    const float rad = float(brick_h) * (0.25f + 0.1f * hash01(col, row, 17));
                    const float d = std::sqrt((dx - ox) * (dx - ox) + dy * dy) / rad;
                    if (d < 1.0f)
                        h -= 0.45f * (1.0f - d * d);
                    else if (d < 1.4f)
                        h += 0.12f * std::sin(float(M_PI) * (d - 1.0f) / 0.4f);
                }
            }
            f.heights[size_t(y) * size + size_t(x)] = std::clamp(h, 0.0f, 1.0f);
        }
    return f;
}

} // namespace hemi::samples
