#version 450
// PRT material, fragment stage (Sloan 2006 Sec. 3): the coefficients are already in the vertex's tangent
// frame, so the normal-map normal evaluates the basis directly: out = albedo * sum_k c_k b_k(n) / pi, with
// albedo = the uniform factor times the base colour texture.
// Attachment 1 carries (u, v, 0, 1) where the mesh covers the pixel.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#define HEMI_PRT_MATERIAL_AUX 1
#include "hemi/materials/prt_material_fs.glsl"
