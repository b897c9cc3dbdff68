// The three directions of radiosity normal mapping in Valve's order (Source's bumpBasis), shared by C++
// (math::rnm_basis()) and GLSL (the rnm and ssbump techniques). Green 2007 Eq. (1) prints two identical
// directions; these are the corrected ones.
#ifndef HEMI_SHARED_RNM_H
#define HEMI_SHARED_RNM_H

#define HEMI_RNM_SQRT_2_3 0.816496580927726 // sqrt(2/3)
#define HEMI_RNM_INV_SQRT_6 0.408248290463863
#define HEMI_RNM_INV_SQRT_2 0.707106781186548
#define HEMI_RNM_INV_SQRT_3 0.577350269189626
#define HEMI_RNM_SQRT_3 1.732050807568877 // the dynamic lights' normalisation of a flat SSBump texel
// B0 = ( sqrt(2/3),        0, 1/sqrt 3)
// B1 = (-1/sqrt 6,  1/sqrt 2, 1/sqrt 3)
// B2 = (-1/sqrt 6, -1/sqrt 2, 1/sqrt 3)

#endif
