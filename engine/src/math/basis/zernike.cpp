// Zernike polynomials on the hemisphere (Koenderink et al. 1996): the unit disk is mapped to the hemisphere
// by the equal-area map rho = sqrt(1 - cos theta), so d(omega) = 2 rho d(rho) d(phi) and disk-orthogonal
// polynomials stay orthogonal. Bands n = 0 {1}, n = 1 {rho cos phi, rho sin phi}, n = 2 {2 rho^2 - 1,
// rho^2 cos 2phi, rho^2 sin 2phi}; in Cartesian form rho cos phi = x / sqrt(1 + z),
// rho^2 cos 2phi = (x^2 - y^2) / (1 + z), 2 rho^2 - 1 = 1 - 2z (the negative of H^3's shape, as Habel &
// Wimmer 2010 Sec. 2.3 note). Normalised on the hemisphere: int_H R^2 = 2pi/(n+1) (m = 0), pi/(n+1) (m != 0).
#include <hemi/math/basis.h>

#include <algorithm>
#include <cmath>

namespace hemi::math::basis_detail
{
static void eval_zernike(const glm::vec3& n, float* out, int count)
{
    const float inv = 1.0f / (1.0f + std::max(0.0f, n.z));
    const float r = std::sqrt(inv);
    out[0] = 0.398942280401433f;           // 1 / sqrt(2 pi)
    out[1] = 0.797884560802865f * n.x * r; // sqrt(2 / pi) rho cos phi
    out[2] = 0.797884560802865f * n.y * r; // sqrt(2 / pi) rho sin phi
    if (count == 6)
    {
        out[3] = 0.690988298942671f * (1.0f - 2.0f * n.z);           // sqrt(3 / (2 pi)) (2 rho^2 - 1)
        out[4] = 0.977205023805840f * (n.x * n.x - n.y * n.y) * inv; // sqrt(3 / pi) rho^2 cos 2phi
        out[5] = 0.977205023805840f * 2.0f * n.x * n.y * inv;        // sqrt(3 / pi) rho^2 sin 2phi
    }
}
static void eval_zernike3(const glm::vec3& n, float* out)
{
    eval_zernike(n, out, 3);
}
static void eval_zernike6(const glm::vec3& n, float* out)
{
    eval_zernike(n, out, 6);
}
extern const BasisDesc k_zernike3{HEMI_BASIS_ZERNIKE3, "zernike3", HEMI_BASIS_SIZE_ZERNIKE3, true,
                                  eval_zernike3};
extern const BasisDesc k_zernike6{HEMI_BASIS_ZERNIKE6, "zernike6", HEMI_BASIS_SIZE_ZERNIKE6, true,
                                  eval_zernike6};
} // namespace hemi::math::basis_detail
