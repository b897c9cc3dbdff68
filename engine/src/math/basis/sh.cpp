// SH9 on the hemisphere (the gold standard) and linear SH least-squares projected on the hemisphere
// (Habel & Wimmer 2010, Sec. 4.1: the same error as H4, but not orthogonal there).
#include <hemi/math/basis.h>
#include <hemi/math/sh.h>

namespace hemi::math::basis_detail
{
static void eval_sh9(const glm::vec3& n, float* out)
{
    Sh9 y = sh9_eval(n);
    for (int i = 0; i < 9; ++i)
        out[i] = y[i];
}
static void eval_sh4(const glm::vec3& n, float* out)
{
    Sh9 y = sh9_eval(n);
    for (int i = 0; i < 4; ++i)
        out[i] = y[i];
}
extern const BasisDesc k_sh9{HEMI_BASIS_SH9, "sh9", HEMI_BASIS_SIZE_SH9, false, eval_sh9};
extern const BasisDesc k_sh4ls{HEMI_BASIS_SH4LS, "sh4ls", HEMI_BASIS_SIZE_SH4LS, false, eval_sh4};
} // namespace hemi::math::basis_detail
