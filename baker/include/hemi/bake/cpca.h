#pragma once
// Clustered principal component analysis (Sloan, Hall, Hart, Snyder, "Clustered Principal Components for
// Precomputed Radiance Transfer", SIGGRAPH 2003): the N per-vertex transfer matrices, seen as points in
// D = K * L dimensions, are split into C clusters, each approximated by its mean plus V principal
// directions; a vertex stores its cluster and V weights. The per-frame work becomes (V + 1) matrix-vector
// products per cluster and V multiply-adds of K RGB vectors per vertex.
//
// Clusters start from a deterministic farthest-point seeding and are refined as in the paper's iterative
// CPCA: fit (mean + PCA by Eigen's self-adjoint eigensolver) per cluster, then move each vertex to the
// cluster that reconstructs it best, until no vertex moves or `iterations` is reached.

#include <hemi/io/prt_asset.h>

#include <cstdint>
#include <span>

namespace hemi::bake
{

// `matrices`: N x D row-major. V is capped at D. Throws std::invalid_argument when N * D does not match the
// span, C is 0 or above N, V is 0, or a value is not finite.
io::PrtCpca compress_cpca(std::span<const float> matrices, uint32_t vertex_count, uint32_t dimension,
                          uint32_t clusters, uint32_t vectors, int iterations = 8);

// Vertex v's matrix rebuilt from the CPCA data (D floats).
void reconstruct_cpca(const io::PrtCpca& cpca, uint32_t dimension, uint32_t vertex, std::span<float> out);

} // namespace hemi::bake
