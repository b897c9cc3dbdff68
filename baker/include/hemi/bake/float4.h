#pragma once
// Four floats to a vector, in GCC's and Clang's vector extensions (SSE's width, which every x86-64 has, and
// NEON's): what the bake's loops over small arrays are written in where the compiler would not vectorise
// them itself (a comparison of floats may trap under the default -ftrapping-math, so a loop with one stays
// scalar, and std::exp is a call per value). Every operation is lane by lane, so a result does not depend on
// how the work is split.

#include <bit>
#include <cstdint>
#include <cstring>

namespace hemi::bake
{

using f32x4 = float __attribute__((vector_size(16)));
using i32x4 = int32_t __attribute__((vector_size(16)));

inline f32x4 splat(float x)
{
    return f32x4{x, x, x, x};
}
inline f32x4 load4(const float* p)
{
    f32x4 v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
inline void store4(float* p, f32x4 v)
{
    std::memcpy(p, &v, sizeof v);
}

// e^x for x <= 0, in float to within 1 ulp (Cody and Waite's reduction, Cephes's polynomial; the worst of 2e7
// values against double's exp: 0.99 ulp); 0 below -87 and for NaN (float's normal range ends at e^-87.3), 1
// above 0. No call and no branch.
inline f32x4 exp_nonpositive(f32x4 x)
{
    const f32x4 in = x >= -87.0f ? (x < 0.0f ? x : f32x4{}) : splat(-87.0f); // (no NaN reaches the int)
    const f32x4 n = (in * 1.44269504f + 12582912.0f) - 12582912.0f; // round(x / ln 2), 1.5 * 2^23's trick
    const f32x4 r = (in - n * 0.693359375f) - n * -2.12194440e-4f;  // x - n ln 2, ln 2 in two parts
    f32x4 p = splat(1.9875691500e-4f);
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    p = p * r * r + r + 1.0f;
    const i32x4 e = (__builtin_convertvector(n, i32x4) + 127) << 23; // 2^n (n >= -126)
    return x >= -87.0f ? p * std::bit_cast<f32x4>(e) : f32x4{};
}

// ln x for a normal x > 0 (not 0, a subnormal, infinity or NaN), in float to within 1 ulp (Cephes's reduction
// to [sqrt(1/2), sqrt(2)) and polynomial; the worst of 2e7 values against double's log: 0.82 ulp); exactly 0
// at 1.
inline f32x4 log_positive(f32x4 x)
{
    const i32x4 bits = std::bit_cast<i32x4>(x), mantissa = (bits & 0x007fffff) | 0x3f000000;
    f32x4 e = __builtin_convertvector(((bits >> 23) & 0xff) - 126, f32x4);
    f32x4 m = std::bit_cast<f32x4>(mantissa); // x = m 2^e, m in [1/2, 1)
    const i32x4 low = m < 0.707106781186547524f;
    e = low ? e - 1.0f : e;
    m = low ? m + m - 1.0f : m - 1.0f;
    const f32x4 z = m * m;
    f32x4 y = splat(7.0376836292e-2f);
    y = y * m - 1.1514610310e-1f;
    y = y * m + 1.1676998740e-1f;
    y = y * m - 1.2420140846e-1f;
    y = y * m + 1.4249322787e-1f;
    y = y * m - 1.6668057665e-1f;
    y = y * m + 2.0000714765e-1f;
    y = y * m - 2.4999993993e-1f;
    y = y * m + 3.3333331174e-1f;
    y = y * m * z + e * -2.12194440e-4f - 0.5f * z;
    return m + y + e * 0.693359375f;
}

} // namespace hemi::bake
