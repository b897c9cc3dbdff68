// Real spherical-harmonic normalisation constants (Condon-Shortley phase, index i = l(l+1)+m) and the
// clamped-cosine convolution factors, shared by C++ and GLSL (DESIGN.md Sec. 3).
#ifndef HEMI_SHARED_SH_CONSTANTS_H
#define HEMI_SHARED_SH_CONSTANTS_H

#define HEMI_SH_Y00 0.28209479177387814 // 1/(2 sqrt(pi))
#define HEMI_SH_Y1 0.4886025119029199   // sqrt(3/(4 pi))
#define HEMI_SH_Y2 1.0925484305920792   // sqrt(15/(4 pi))
#define HEMI_SH_Y20 0.31539156525252005 // sqrt(5/(16 pi))
#define HEMI_SH_Y22 0.5462742152960396  // sqrt(15/(16 pi))

// Funk-Hecke factors of the clamped cosine: A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4.
#define HEMI_SH_A0 3.141592653589793
#define HEMI_SH_A1 2.0943951023931953
#define HEMI_SH_A2 0.7853981633974483

#endif
