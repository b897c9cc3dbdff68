// Shifted associated Legendre basis (Gautron et al. 2004's hemispherical harmonics), the first four
// functions as printed in Sloan 2006 Sec. 3.1. sqrt(z - z^2) / sqrt(1 - z^2) is written sqrt(z / (1 + z)),
// which has no 0/0 at the pole.
#include <hemi/math/basis.h>

#include <algorithm>
#include <cmath>

namespace hemi::math::basis_detail
{
static void eval_sal4(const glm::vec3& n, float* out)
{
    const float k0 = 0.398942280401433f; // sqrt2 / (2 sqrt pi)
    const float k1 = 0.690988298942671f; // sqrt6 / (2 sqrt pi)
    const float k2 = 1.381976597885342f; // sqrt6 / sqrt pi
    float s = std::sqrt(std::max(0.0f, n.z) / (1.0f + std::max(0.0f, n.z)));
    out[0] = k0;
    out[1] = -k2 * s * n.y;
    out[2] = k1 * (2.0f * n.z - 1.0f);
    out[3] = -k2 * s * n.x;
}
extern const BasisDesc k_sal4{HEMI_BASIS_SAL4, "sal4", HEMI_BASIS_SIZE_SAL4, true, eval_sal4};
} // namespace hemi::math::basis_detail
