// hemi-bake built without MPI (CMake found none, or -DHEMI_WITH_MPI=OFF): every run is one process.
#include "mpi_distribution.h"

namespace hemi::tool
{

std::unique_ptr<MpiJob> join_mpi_job(int&, char**&)
{
    return nullptr;
}

} // namespace hemi::tool
