#pragma once
// The per-frame PRT transfer multiply, c_v = T_v * l (Sloan 2006, Sec. 2): on the Vulkan device
// (TransferPass) and on the host (transfer_multiply_host), over one shared data layout.
//
// T_v is a K x L matrix per vertex (K output coefficients of the pixel basis: 3 HL2, 4 SAL/H4/separable,
// 6 H6, 9 SH; L lighting SH coefficients: 9, 16, 25 or 36), l is the RGB lighting in SH (L vec3), and
// c_v is K RGB coefficients. Output layout on both paths: coefficient k of vertex v is the 4 floats at
// (v*K + k)*4 (r, g, b, 0) -- one RGBA32F texel, what a vertex shader reads with texelFetch.

#include <hemi/gpu/commands.h>
#include <hemi/gpu/device.h>
#include <hemi/gpu/pipeline.h>
#include <hemi/gpu/resources.h>

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hemi::render
{

// Per-vertex transfer matrices in hemi's element-interleaved block layout (hemi/shared/transfer.h):
// blocks of 32 vertices; inside a block, element f = k*L + j of all 32 vertices is 32 consecutive floats.
// The last block is padded with zero matrices.
class TransferMatrices
{
public:
    // `row_major` holds N matrices one after another, each K x L row-major (element (k, j) at k*L + j).
    // Throws std::invalid_argument when N is 0, K is not in [1, 9], L is not a square in [1, 36], the
    // span's size is not N*K*L, or a value is not finite.
    TransferMatrices(uint32_t vertex_count, uint32_t k, uint32_t l, std::span<const float> row_major);

    uint32_t vertex_count() const { return n_; }
    uint32_t k() const { return k_; }
    uint32_t l() const { return l_; }
    uint32_t block_count() const { return blocks_; }
    // Floats of one 32-vertex block: K * L * 32.
    size_t block_floats() const { return size_t(k_) * l_ * kBlockVertices; }
    std::span<const float> data() const { return data_; }
    // Bytes of the matrices proper, N*K*L*4: what the bandwidth ratios of hemi-bench are measured against.
    size_t matrix_bytes() const { return size_t(n_) * k_ * l_ * sizeof(float); }
    // Element (k, j) of vertex v (for tests and tools; not for hot loops).
    float at(uint32_t v, uint32_t k, uint32_t j) const;

    static constexpr uint32_t kBlockVertices = 32;

private:
    uint32_t n_, k_, l_, blocks_;
    std::vector<float> data_;
};

// Throws std::invalid_argument with a message naming the mismatch.
void validate_transfer_shape(uint32_t vertex_count, uint32_t k, uint32_t l);

// Host path: writes c_v for every vertex into `out` (size N*K*4 floats, layout above). `lighting` has L
// entries. Vectorised over the 32 vertices of a block (AVX2+FMA when the CPU has it) and multi-threaded
// over blocks with TBB. Throws std::invalid_argument on size mismatches.
void transfer_multiply_host(const TransferMatrices& matrices, std::span<const glm::vec3> lighting,
                            std::span<float> out);

// What a PRT material reads: per-vertex basis coefficients on the device (texel v*K + k, RGBA32F), written
// each frame from the lighting by a compute pass. TransferPass (dense matrices) and CpcaTransferPass (CPCA)
// are the two sources; the materials take either.
class CoefficientSource
{
public:
    virtual ~CoefficientSource() = default;
    // Records the lighting update and the compute work. The caller orders later reads of coefficients()
    // with a barrier from VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT / VK_ACCESS_SHADER_WRITE_BIT.
    // `lighting` holds L finite entries per instance, for 1 to instances() instances (instance i's at
    // i * L): every instance shares the matrices and is relit with its own lighting (each object's
    // environment rotated into its frame), into its own coefficients at instance_offset(i).
    virtual void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting) = 0;
    virtual uint32_t instances() const = 0;
    // Texels between two instances' coefficients (>= N*K, aligned for texel-buffer views).
    virtual uint64_t instance_stride() const = 0;
    uint64_t instance_offset(uint32_t instance) const { return instance * instance_stride(); }
    // Records, submits and waits (with the coefficients made visible to the host): for tools and tests.
    void run(std::span<const glm::vec3> lighting);
    virtual const gpu::Buffer& coefficients() const = 0;
    // Reads instance 0's coefficients back (N*K*4 floats).
    std::vector<float> read_coefficients() const;
    virtual uint32_t vertex_count() const = 0;
    virtual uint32_t k() const = 0;
    virtual uint32_t l() const = 0;
    virtual const gpu::Device& device() const = 0;
};

// Device path. Owns the matrices' GPU copy, the lighting uniform buffer, the output coefficient buffer and
// the compute pipeline; one dispatch per segment of at most maxTexelBufferElements texels.
class TransferPass : public CoefficientSource
{
public:
    // `max_view_texels` bounds the texels of one texel-buffer view (and so one dispatch's segment);
    // 0 means the device's maxTexelBufferElements. Smaller values exist to exercise segmenting in tests.
    // `instances` objects can be relit per frame from the one copy of the matrices.
    TransferPass(const gpu::Device& device, const TransferMatrices& matrices, uint64_t max_view_texels = 0,
                 uint32_t instances = 1);
    ~TransferPass();
    TransferPass(const TransferPass&) = delete;
    TransferPass& operator=(const TransferPass&) = delete;

    // Records: the lighting update (vkCmdUpdateBuffer, so no host synchronisation is needed between
    // frames), a barrier, and the dispatches. The caller orders later reads of coefficients() with a
    // barrier from VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT / VK_ACCESS_SHADER_WRITE_BIT.
    // `lighting` must have L entries of finite values.
    void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting) override;

    // RGBA32F texels: coefficient k of vertex v is texel v*K + k. Usable as a uniform texel buffer.
    const gpu::Buffer& coefficients() const override;

    uint32_t vertex_count() const override;
    uint32_t k() const override;
    uint32_t l() const override;
    const gpu::Device& device() const override;
    uint32_t segment_count() const;
    uint32_t instances() const override;
    uint64_t instance_stride() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// Matrices compressed with CPCA (Sloan et al. 2003): C clusters, each a mean and V PCA matrices (K x L, the
// same row-major form as TransferMatrices' input), and per vertex a cluster and V weights.
struct CpcaMatrices
{
    uint32_t vertex_count = 0, k = 0, l = 0, clusters = 0, vectors = 0;
    std::span<const float> means;      // C x K*L
    std::span<const float> basis;      // C x V x K*L
    std::span<const uint32_t> cluster; // N
    std::span<const float> weights;    // N x V
};

// The CPCA multiply on the host (Eigen GEMM per block of vertices for one cluster, a GEMV per vertex for
// several; TBB over blocks): same output layout as transfer_multiply_host. Checks sizes and cluster ids on
// every call; the values' finiteness is checked where data enter (CpcaTransferPass, io::read_prt_asset), not
// per frame.
void cpca_multiply_host(const CpcaMatrices& cpca, std::span<const glm::vec3> lighting, std::span<float> out);

// The CPCA path on the device: a small dispatch projecting every cluster's mean and PCA matrices on the
// lighting ((V + 1) * K RGB values per cluster), then one invocation per vertex summing its V weighted
// projections. The per-frame memory traffic per vertex is V weights instead of K * L matrix elements.
class CpcaTransferPass : public CoefficientSource
{
public:
    // Throws std::invalid_argument on inconsistent sizes, a cluster out of range or a non-finite value, and
    // std::runtime_error when the data exceed the device's storage-buffer range or texel-buffer size.
    CpcaTransferPass(const gpu::Device& device, const CpcaMatrices& cpca, uint32_t instances = 1);
    ~CpcaTransferPass();
    CpcaTransferPass(const CpcaTransferPass&) = delete;
    CpcaTransferPass& operator=(const CpcaTransferPass&) = delete;

    void record(VkCommandBuffer cmd, std::span<const glm::vec3> lighting) override;
    const gpu::Buffer& coefficients() const override;
    uint32_t vertex_count() const override;
    uint32_t k() const override;
    uint32_t l() const override;
    const gpu::Device& device() const override;
    uint32_t instances() const override;
    uint64_t instance_stride() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace hemi::render
