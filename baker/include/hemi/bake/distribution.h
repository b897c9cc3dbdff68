#pragma once
// Who computes a bake's slices: this process's threads (local_distribution(), the default), or the processes
// ("ranks") of a job spread over machines: hemi-bake's Open MPI one (baker/cli/mpi_distribution.h, under
// mpirun), or a studio's own farm behind the same interface.
//
// A bake that fits it works as SliceCheckpoint describes (checkpoint.h): passes over `items` items (texels,
// vertices), each item's result depending only on the scene, the options and the previous passes, written
// into per-item arrays. A pass is handed to run(): its slices go to the ranks as they ask for work (so fast
// and slow ranks finish together), and when run() returns every rank holds every item of the pass's arrays,
// bit for bit what the rank that computed it left there. Since no item's value depends on where or when it
// was computed, the bake gives the same bytes for any number of ranks and threads.
//
// Rank 0 (the leader) is the one that resumes and saves the checkpoint, reports progress and writes the
// outputs; the others compute and receive.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::bake
{

// One of a pass's per-item arrays: item i at data + i * item_bytes.
struct ItemArray
{
    std::byte* data = nullptr;
    size_t item_bytes = 0;
};

class Distribution
{
  public:
    virtual ~Distribution() = default;

    virtual uint32_t rank() const = 0;
    virtual uint32_t ranks() const = 0;
    bool leader() const { return rank() == 0; }

    // Computes items [first, items) in slices of `slice` items (the last may be shorter; first, items and
    // slice are the same on every rank): compute(begin, end) fills those items of `arrays` on whichever rank
    // runs it. Returns when every item of [first, items) is in `arrays` on every rank. On the leader,
    // `finished` is called with next each time the finished prefix [first, next) grows (next < items; the
    // caller knows when the pass is whole), so that a checkpoint saves only finished work.
    virtual void run(uint32_t first, uint32_t items, uint32_t slice, std::span<const ItemArray> arrays,
                     const std::function<void(uint32_t begin, uint32_t end)>& compute,
                     const std::function<void(uint32_t next)>& finished) = 0;

    // The leader's bytes, to every rank (a resumed checkpoint's state). The same size on every rank.
    virtual void broadcast(std::span<std::byte> bytes) = 0;
    // Jobs whose results are bytes of any size (a lightmap's outputs, each made, stitched and encoded):
    // job(i) for i in [0, count) runs on rank i % ranks(), and the leader takes every result in the order of
    // i, through take(i, bytes): its own as it makes them, the others' as they arrive. take is called on the
    // leader only. The same count on every rank. This process alone (the default): take(i, job(i)) in turn.
    virtual void run_jobs(uint32_t count, const std::function<std::vector<std::byte>(uint32_t)>& job,
                          const std::function<void(uint32_t, std::vector<std::byte>&&)>& take)
    {
        for (uint32_t i = 0; i < count; ++i)
            take(i, job(i));
    }

    // Throws std::runtime_error on a rank whose `value` (a bake's checkpoint key: a hash of its inputs and
    // options) differs from the leader's: ranks that would bake different scenes must not share slices.
    void check_same(uint64_t value, const std::string& what);

    // On the leader: how many items each rank has computed in run() so far (the load balance, for reports).
    virtual std::vector<uint64_t> items_by_rank() const = 0;
};

// This process alone: the slices in order, one after the other (each computed on the process's threads).
Distribution& local_distribution();

} // namespace hemi::bake
