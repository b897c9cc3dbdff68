// hemi's shading library for an engine's own shaders: #include "hemi/hemi.glsl" (with
// GL_GOOGLE_include_directive, the install's include/ directory on glslang's include path) and call its
// functions with the engine's own inputs. It declares no descriptors, inputs, outputs or push constants:
// where a function reads a texture the engine passes its own sampler. hemi's material system's surface
// shader (shaders/surface.frag) is one user of it. docs/glsl.md lists every function.
//
//   hemi/lib/frame.glsl         tangent frames (glTF), normal-map normals, normal matrices
//   hemi/lib/coefficients.glsl  coefficients from a lightmap, a per-vertex (PRT) buffer, varyings
//   hemi/lib/irradiance.glsl    E(n) for every basis of math::bases(), SH9 probes
//   hemi/lib/probes.glsl        SH9 light probes blended over the probes a point can see
//   hemi/lib/rnm.glsl           radiosity normal mapping and SSBump (Green 2007)
//   hemi/lib/environment.glsl   parabolic environment maps, Fresnel and BRDF tables (Heidrich & Seidel 1999)
//   hemi/lib/lights.glsl        the dynamic-light terms hemi's techniques use
//   hemi/lib/specular.glsl      GGX, and specular light from a basis's coefficients (directional lightmaps)
#ifndef HEMI_HEMI_GLSL
#define HEMI_HEMI_GLSL
#include "hemi/lib/coefficients.glsl"
#include "hemi/lib/environment.glsl"
#include "hemi/lib/frame.glsl"
#include "hemi/lib/irradiance.glsl"
#include "hemi/lib/lights.glsl"
#include "hemi/lib/probes.glsl"
#include "hemi/lib/rnm.glsl"
#include "hemi/lib/specular.glsl"
#endif
