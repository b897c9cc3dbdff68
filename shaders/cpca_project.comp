#version 450
// CPCA transfer, step 1 (Sloan et al. 2003; Sloan 2006 Sec. 2): per cluster, the mean matrix and each PCA
// matrix times the lighting. Row r of the (C * (V + 1) * K) x L row set is one output: projected[r] = rows[r]
// . l. A small dispatch: C * (V + 1) * K invocations, each an L-term dot product per colour. Each cluster's
// results start at an aligned stride: step 2 binds them as a uniform block at a dynamic offset.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
#include "hemi/shared/transfer.h"

layout(constant_id = 0) const uint L = 25;

layout(local_size_x = HEMI_TRANSFER_WORKGROUP_SIZE) in;

layout(set = 0, binding = HEMI_CPCA_BINDING_ROWS, std430) readonly buffer Rows
{
    float rows[];
};
layout(set = 0, binding = HEMI_CPCA_BINDING_LIGHTING, std140) uniform Lighting
{
    vec4 light[HEMI_TRANSFER_MAX_L];
};
layout(set = 0, binding = HEMI_CPCA_BINDING_PROJECTED, std430) writeonly buffer Projected
{
    vec4 projected[];
};

layout(push_constant) uniform Push
{
    CpcaPush pc;
};

void main()
{
    uint r = gl_GlobalInvocationID.x;
    if (r >= pc.count)
        return;
    vec3 sum = vec3(0.0);
    [[unroll]] for (uint j = 0; j < L; ++j) sum += rows[r * L + j] * light[j].rgb;
    projected[(r / pc.per_cluster) * pc.stride + r % pc.per_cluster] = vec4(sum, 0.0);
}
