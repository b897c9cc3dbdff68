// Constants and push-constant layout of the PRT transfer pass, shared by C++ and GLSL.
#ifndef HEMI_SHARED_TRANSFER_H
#define HEMI_SHARED_TRANSFER_H

#ifdef __cplusplus
#include <cstdint>
#define HEMI_UINT uint32_t
#else
#define HEMI_UINT uint
#endif

// Transfer matrices are stored in blocks of 32 vertices, element-interleaved: for element f = k*L + j of
// the K x L matrix, the 32 vertices' values are 32 consecutive floats. One RGBA32F texel therefore holds
// element f of 4 consecutive vertices, and one invocation computes 4 vertices with vec4 arithmetic.
#define HEMI_TRANSFER_BLOCK_VERTICES 32
#define HEMI_TRANSFER_VERTICES_PER_INVOCATION 4
#define HEMI_TRANSFER_INVOCATIONS_PER_BLOCK                                                                  \
    (HEMI_TRANSFER_BLOCK_VERTICES / HEMI_TRANSFER_VERTICES_PER_INVOCATION)
#define HEMI_TRANSFER_WORKGROUP_SIZE 64
#define HEMI_TRANSFER_MAX_K 9
#define HEMI_TRANSFER_MAX_L 36

#define HEMI_TRANSFER_BINDING_MATRICES 0
#define HEMI_TRANSFER_BINDING_LIGHTING 1
#define HEMI_TRANSFER_BINDING_COEFFICIENTS 2

struct TransferPush
{
    HEMI_UINT vertex_count; // vertices in this dispatch's segment
};

// The CPCA path (cpca_project.comp, then cpca_reconstruct.comp).
#define HEMI_CPCA_BINDING_ROWS 0
#define HEMI_CPCA_BINDING_LIGHTING 1
#define HEMI_CPCA_BINDING_PROJECTED 2
#define HEMI_CPCA_BINDING_WEIGHTS 3
#define HEMI_CPCA_BINDING_COEFFICIENTS 5
#define HEMI_CPCA_BINDING_SLOTS 4
// PCA vectors per cluster the runtime pass supports (its uniform block holds one cluster's projections).
#define HEMI_CPCA_MAX_VECTORS 64
// Size of the uniform block holding one cluster's projections (std140 vec4 array).
#define HEMI_CPCA_PROJECTED_BYTES (HEMI_TRANSFER_MAX_K * (HEMI_CPCA_MAX_VECTORS + 1) * 16)

struct CpcaPush
{
    HEMI_UINT count;       // rows to project (step 1) or invocations of this cluster's dispatch (step 2)
    HEMI_UINT first;       // step 2: the cluster's first invocation (slots / 4)
    HEMI_UINT per_cluster; // step 1: rows per cluster, (V + 1) * K
    HEMI_UINT stride;      // step 1: vec4s between two clusters' projections (aligned for dynamic offsets)
};

#ifdef __cplusplus
#undef HEMI_UINT
#endif

#endif
