#pragma once
// The per-frame transfer on the host: the same products and output layout as the device passes
// (passes/transfer_pass.h, passes/cpca_pass.h), for engines that multiply on the CPU and upload.

#include <hemi/render/passes/transfer_matrices.h>

#include <glm/vec3.hpp>

#include <span>

namespace hemi::render
{

// Host path: writes c_v for every vertex into `out` (size N*K*4 floats, layout above). `lighting` has L
// entries. Vectorised over the 32 vertices of a block (AVX2+FMA when the CPU has it) and multi-threaded
// over blocks with TBB. Throws std::invalid_argument on size mismatches.
void transfer_multiply_host(const TransferMatrices& matrices, std::span<const glm::vec3> lighting,
                            std::span<float> out);

// The CPCA multiply on the host (Eigen GEMM per block of vertices for one cluster, a GEMV per vertex for
// several; TBB over blocks): same output layout as transfer_multiply_host. Checks sizes and cluster ids on
// every call; the values' finiteness is checked where data enter (CpcaTransferPass, io::read_prt_asset), not
// per frame.
void cpca_multiply_host(const CpcaMatrices& cpca, std::span<const glm::vec3> lighting, std::span<float> out);

} // namespace hemi::render
