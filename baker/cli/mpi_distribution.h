#pragma once
// hemi-bake's bakes spread over the ranks of an Open MPI job (bake/distribution.h): `mpirun -np N hemi-bake
// lightmap ...`. Rank 0 hands the slices of each pass out as ranks ask for more (each rank keeps three in
// hand, so none waits on the leader), computes slices itself between messages, and sends every rank the whole
// pass when it is done. Built only when CMake finds MPI (HEMI_WITH_MPI); without it hemi-bake is the one
// process it always was. docs/distributed.md shows mpirun, a hostfile and a Slurm script.
#include <hemi/bake/distribution.h>

#include <memory>

namespace hemi::tool
{

class MpiJob : public bake::Distribution
{
  public:
    virtual ~MpiJob() = default;
    // Ends the whole job with `code` (MPI_Abort): after an error on any rank, so that no rank waits forever
    // for one that has stopped.
    [[noreturn]] virtual void abort(int code) = 0;
};

// The job this process belongs to, after MPI_Init, when it was started by mpirun (or another MPI launcher:
// PMIx's or Slurm's environment); null when it was started on its own, or hemi-bake was built without MPI.
// MPI_Finalize runs when the job object is destroyed.
std::unique_ptr<MpiJob> join_mpi_job(int& argc, char**& argv);

} // namespace hemi::tool
