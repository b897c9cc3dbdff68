#pragma once
// Light of any magnitude in half floats. A lightmap's coefficients are stored as IEEE binary16 (the asset,
// the runtime's RGBA16F pages, hemi-bake export's RGB16F outputs): 11 significant bits, at most 65504, normal
// down to 6.1e-5. A real sky with its sun (10^5 lux) or a dim moonlit scene leaves that window, so each set
// of values stored as halves carries a power-of-two scale 2^e: the stored half is value / 2^e and the value
// is half * 2^e. A power of two changes no significant bit, so the halves hold every value to the same
// relative precision (2^-11) whatever the light's magnitude, and a scene whose values already fit
// ([2^-6, 2^15]: every lightmap of a scene lit in the ordinary units around 1) keeps e = 0 and the bytes it
// always had.

#include <algorithm>
#include <cmath>
#include <span>

namespace hemi::io
{

// The exponents a stored scale may have: what a float holds with room on both sides.
inline constexpr int kMinHalfScaleExponent = -100;
inline constexpr int kMaxHalfScaleExponent = 112;

// The largest |v| of `values` (0 for none; non-finite values are the caller's to refuse).
inline float largest_magnitude(std::span<const float> values)
{
    float m = 0.0f;
    for (float v : values)
        m = std::max(m, std::abs(v));
    return m;
}

// The exponent e of the scale 2^e for values whose largest magnitude is `largest`: 0 when it lies in
// [2^-6, 2^15] (or is 0), else the e that brings it into (2^13, 2^14], which leaves the halves a factor of 4
// of headroom and 2^27 of range below it. Clamped to [kMinHalfScaleExponent, kMaxHalfScaleExponent].
inline int half_scale_exponent(float largest)
{
    if (!(largest > 0.0f) || !std::isfinite(largest) || (largest >= 0x1p-6f && largest <= 0x1p15f))
        return 0;
    int e = 0;
    const float m = std::frexp(largest, &e); // largest = m 2^e, m in [0.5, 1)
    if (m == 0.5f)
        --e; // an exact power of two 2^(e - 1)
    // Now largest <= 2^e (and > 2^(e - 1)); divided by 2^(e - 14) it lies in (2^13, 2^14].
    return std::clamp(e - 14, kMinHalfScaleExponent, kMaxHalfScaleExponent);
}

} // namespace hemi::io
