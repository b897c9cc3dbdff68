// The H-basis of Habel & Wimmer 2010, Eq. (8)-(13): SH functions without explicit z, scaled by sqrt(2) to be
// orthonormal on the hemisphere, plus the shifted y1,0 (cos theta -> 2 cos theta - 1). H4 = H^1..H^4.
#include <hemi/math/basis.h>

namespace hemi::math::basis_detail
{
static void eval_h(const glm::vec3& n, float* out, int count)
{
    const float k0 = 0.398942280401433f; // 1 / sqrt(2 pi)
    const float k1 = 0.690988298942671f; // sqrt(3 / (2 pi))
    const float k2 = 1.545096808092680f; // sqrt(15 / (2 pi))
    out[0] = k0;
    out[1] = -k1 * n.y;
    out[2] = k1 * (2.0f * n.z - 1.0f);
    out[3] = -k1 * n.x;
    if (count == 6)
    {
        out[4] = k2 * n.x * n.y;
        out[5] = 0.5f * k2 * (n.x * n.x - n.y * n.y);
    }
}
static void eval_h4(const glm::vec3& n, float* out)
{
    eval_h(n, out, 4);
}
static void eval_h6(const glm::vec3& n, float* out)
{
    eval_h(n, out, 6);
}
extern const BasisDesc k_h4{HEMI_BASIS_H4, "h4", HEMI_BASIS_SIZE_H4, true, eval_h4};
extern const BasisDesc k_h6{HEMI_BASIS_H6, "h6", HEMI_BASIS_SIZE_H6, true, eval_h6};
} // namespace hemi::math::basis_detail
