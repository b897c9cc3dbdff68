// Ids and sizes of hemi's hemispherical bases, shared by C++ and GLSL. The C++ descriptions live in
// engine/src/math/basis/, the GLSL twins in shaders/include/hemi/basis/; a GPU test holds them equal.
#ifndef HEMI_SHARED_BASES_H
#define HEMI_SHARED_BASES_H

#define HEMI_BASIS_SH9 0       // quadratic SH, the "gold standard"
#define HEMI_BASIS_SH4LS 1     // linear SH, least-squares projected on the hemisphere
#define HEMI_BASIS_HL2 2       // Half-Life 2: 3 unclamped cosine lobes, orthonormal on the hemisphere
#define HEMI_BASIS_H4 3        // Habel & Wimmer 2010 H-basis, 4 functions
#define HEMI_BASIS_H6 4        // H-basis, 6 functions
#define HEMI_BASIS_SAL4 5      // shifted associated Legendre (Gautron's HSH), first 4 functions
#define HEMI_BASIS_ZERNIKE3 6  // Koenderink's hemispherical Zernike basis, bands n <= 1
#define HEMI_BASIS_ZERNIKE6 7  // bands n <= 2
#define HEMI_BASIS_SEP4 8      // Sloan 2006 Sec. 3.2 separable (SVD) basis, 4 terms, convolution folded in
#define HEMI_BASIS_COUNT 9
// Not a hemispherical basis: classic diffuse PRT's single constant function (the coefficient is the
// irradiance at the vertex normal; the normal map is ignored). math::vertex_irradiance_basis().
#define HEMI_BASIS_VERTEX_IRRADIANCE 9

#define HEMI_BASIS_MAX_SIZE 9

#define HEMI_BASIS_SIZE_SH9 9
#define HEMI_BASIS_SIZE_SH4LS 4
#define HEMI_BASIS_SIZE_HL2 3
#define HEMI_BASIS_SIZE_H4 4
#define HEMI_BASIS_SIZE_H6 6
#define HEMI_BASIS_SIZE_SAL4 4
#define HEMI_BASIS_SIZE_ZERNIKE3 3
#define HEMI_BASIS_SIZE_ZERNIKE6 6
#define HEMI_BASIS_SIZE_SEP4 4

#endif
