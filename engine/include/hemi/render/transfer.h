#pragma once
// Everything of the per-frame PRT transfer multiply, c_v = T_v * l (Sloan 2006, Sec. 2), in one include: the
// matrices (passes/transfer_matrices.h), the host multiplies (passes/host_transfer.h) and the device passes
// (passes/coefficient_source.h, passes/transfer_pass.h, passes/cpca_pass.h).
#include <hemi/render/passes/coefficient_source.h>
#include <hemi/render/passes/cpca_pass.h>
#include <hemi/render/passes/host_transfer.h>
#include <hemi/render/passes/transfer_matrices.h>
#include <hemi/render/passes/transfer_pass.h>
