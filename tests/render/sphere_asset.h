#pragma once
// A UV sphere's PRT asset, baked unshadowed at lighting order 3 and folded into one technique: the analytic
// case several render tests light with a single directional light.
#include <hemi/bake/prt_bake.h>
#include <hemi/bake/transfer_fold.h>
#include <hemi/io/prt_asset.h>

#include <string>
#include <utility>

namespace hemi::test
{

inline io::PrtAsset unshadowed_sphere_asset(uint32_t segments, uint32_t rings, const std::string& technique,
                                            uint32_t k)
{
    io::PrtAsset a;
    a.mesh = io::make_uv_sphere(1.0f, segments, rings);
    a.order = 3;
    a.transfer_kind = 0;
    bake::PrtBakeOptions o;
    o.kind = bake::TransferKind::Unshadowed;
    o.order = 3;
    io::PrtTechnique t;
    t.name = technique;
    t.k = k;
    t.matrices = bake::fold_technique(bake::bake_prt_transfer(a.mesh, o), a.mesh, technique);
    a.techniques.push_back(std::move(t));
    return a;
}

} // namespace hemi::test
