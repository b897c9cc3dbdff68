// Half-Life 2 basis (Sloan 2006 Sec. 3.1; Habel & Wimmer 2010 Eq. 1-2): three unclamped cosine lobes
// sqrt(3/(2pi)) (n . h_i), orthonormal over the hemisphere. Direction order as printed in both papers
// (Valve's own order puts the third first, DESIGN.md Sec. 5). Sloan's printed projection matrix weights the
// raw lobes (n . h_i), i.e. it is sqrt(3/(2pi)) times ours.
#include <hemi/math/basis.h>

#include <cmath>

namespace hemi::math::basis_detail
{
static void eval_hl2(const glm::vec3& n, float* out)
{
    const float k = 0.690988298942671f; // sqrt(3 / (2 pi))
    const float a = 0.408248290463863f, b = 0.707106781186548f,
                c = 0.577350269189626f; // 1/sqrt6, 1/sqrt2, 1/sqrt3
    out[0] = k * (-a * n.x - b * n.y + c * n.z);
    out[1] = k * (-a * n.x + b * n.y + c * n.z);
    out[2] = k * (0.816496580927726f * n.x + c * n.z); // sqrt(2/3)
}
extern const BasisDesc k_hl2{HEMI_BASIS_HL2, "hl2", HEMI_BASIS_SIZE_HL2, true, eval_hl2};
} // namespace hemi::math::basis_detail
