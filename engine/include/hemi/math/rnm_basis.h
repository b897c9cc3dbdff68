#pragma once
// The three tangent-space directions of radiosity normal mapping (Half-Life 2's basis), in Valve's order:
// the order of Source's `bumpBasis`, of its three lightmaps and of an SSBump map's three channels. Each lies
// at 1/sqrt(3) height (54.7 degrees from the normal), 120 degrees apart around z; they are orthonormal as a
// set of vectors (sum_i B_i B_i^T = I), so sum_i (n . B_i) B_i = n for any n.
//
// Green 2007 Eq. (1) prints two identical directions; these are the corrected ones (docs/DESIGN.md, errata).
// math::bases()'s "hl2" basis uses the same directions in the order Sloan 2006 and Habel 2010 print them:
// rnm_basis()[0] is hl2's third, [1] its second, [2] its first.

#include "hemi/shared/rnm.h"

#include <glm/vec3.hpp>

#include <array>

namespace hemi::math
{

inline const std::array<glm::vec3, 3>& rnm_basis()
{
    static const std::array<glm::vec3, 3> b = {
        glm::vec3(float(HEMI_RNM_SQRT_2_3), 0.0f, float(HEMI_RNM_INV_SQRT_3)),
        glm::vec3(-float(HEMI_RNM_INV_SQRT_6), float(HEMI_RNM_INV_SQRT_2), float(HEMI_RNM_INV_SQRT_3)),
        glm::vec3(-float(HEMI_RNM_INV_SQRT_6), -float(HEMI_RNM_INV_SQRT_2), float(HEMI_RNM_INV_SQRT_3)),
    };
    return b;
}

} // namespace hemi::math
