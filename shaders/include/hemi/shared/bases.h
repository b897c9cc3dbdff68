// Ids and sizes of hemi's hemispherical bases, shared by C++ and GLSL. The list is generated
// (cmake/HemiBases.cmake) from the "// hemi-basis:" declarations in shaders/include/hemi/basis/*.glsl; the
// C++ descriptions live in engine/src/math/basis/ (one `k_<name>` each), the GLSL twins next to their
// declarations; a GPU test holds every entry of math::bases() equal to its twin.
#ifndef HEMI_SHARED_BASES_H
#define HEMI_SHARED_BASES_H

#include "hemi/shared/bases_generated.h"

// Not a hemispherical basis: classic diffuse PRT's single constant function (the coefficient is the
// irradiance at the vertex normal; the normal map is ignored). math::vertex_irradiance_basis(). Outside the
// range of generated ids.
#define HEMI_BASIS_VERTEX_IRRADIANCE 31

// Paged lightmaps (render::TexelCoefficients, hemi_lightmap_coefficients in hemi/lib/coefficients.glsl): the
// atlas's pages are HEMI_LIGHTMAP_PAGE^2 texels, each stored in a slot of HEMI_LIGHTMAP_SLOT^2 with a border
// of one texel.
#define HEMI_LIGHTMAP_PAGE 64
#define HEMI_LIGHTMAP_SLOT (HEMI_LIGHTMAP_PAGE + 2)

#endif
