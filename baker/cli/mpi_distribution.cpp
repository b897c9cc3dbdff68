#include "mpi_distribution.h"

// The C API only: mpi.h in C++ would also declare the removed C++ bindings (libmpi_cxx).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <list>
#include <stdexcept>
#include <string>
#include <vector>

namespace hemi::tool
{
namespace
{

constexpr int kAssign = 1; // leader -> worker: int64 slice index, or -1: no more in this pass
constexpr int kResult = 2; // worker -> leader: u32 slice index, then the slice's items of every array
constexpr int kInHand = 3; // slices assigned to a worker ahead of its results
constexpr int kJob = 4;    // worker -> leader: u64 size, then a job's result in pieces of at most 1 GiB

void check(int code, const char* what)
{
    if (code != MPI_SUCCESS)
    {
        char text[MPI_MAX_ERROR_STRING];
        int length = 0;
        MPI_Error_string(code, text, &length);
        throw std::runtime_error(std::string("MPI: ") + what +
                                 " failed: " + std::string(text, size_t(length)));
    }
}

class Job final : public MpiJob
{
  public:
    Job(int& argc, char**& argv)
    {
        int provided = 0;
        check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
        int r = 0, n = 1;
        MPI_Comm_rank(MPI_COMM_WORLD, &r);
        MPI_Comm_size(MPI_COMM_WORLD, &n);
        rank_ = uint32_t(r);
        ranks_ = uint32_t(n);
        items_.assign(ranks_, 0);
    }
    ~Job() override { MPI_Finalize(); }

    uint32_t rank() const override { return rank_; }
    uint32_t ranks() const override { return ranks_; }

    [[noreturn]] void abort(int code) override
    {
        MPI_Abort(MPI_COMM_WORLD, code);
        std::_Exit(code);
    }

    void broadcast(std::span<std::byte> bytes) override
    {
        constexpr size_t kChunk = size_t(1) << 30;
        for (size_t at = 0; at < bytes.size(); at += kChunk)
            check(MPI_Bcast(bytes.data() + at, int(std::min(kChunk, bytes.size() - at)), MPI_BYTE, 0,
                            MPI_COMM_WORLD),
                  "MPI_Bcast");
    }

    void run(uint32_t first, uint32_t items, uint32_t slice, std::span<const bake::ItemArray> arrays,
             const std::function<void(uint32_t, uint32_t)>& compute,
             const std::function<void(uint32_t)>& finished) override
    {
        if (ranks_ == 1)
        {
            bake::local_distribution().run(first, items, slice, arrays, compute, finished);
            items_[0] += items - std::min(first, items);
            return;
        }
        if (first >= items)
            return;
        slice = std::max(slice, 1u);
        const uint32_t slices = (items - first + slice - 1) / slice;
        size_t item_bytes = 0;
        for (const bake::ItemArray& a : arrays)
            item_bytes += a.item_bytes;
        if (4 + uint64_t(slice) * item_bytes > uint64_t(INT_MAX))
            throw std::runtime_error("MPI: a slice of " + std::to_string(slice) + " items of " +
                                     std::to_string(item_bytes) + " bytes does not fit one message");
        const auto range = [&](uint32_t s) {
            return std::pair<uint32_t, uint32_t>(first + s * slice, std::min(items, first + (s + 1) * slice));
        };
        if (rank_ == 0)
            lead(slices, range, arrays, compute, finished);
        else
            work(range, arrays, compute);
        // Every rank gets the whole pass.
        for (const bake::ItemArray& a : arrays)
            broadcast({a.data + size_t(first) * a.item_bytes, size_t(items - first) * a.item_bytes});
    }

    void run_jobs(uint32_t count, const std::function<std::vector<std::byte>(uint32_t)>& job,
                  const std::function<void(uint32_t, std::vector<std::byte>&&)>& take) override
    {
        // In order of i on every rank: a worker's blocking sends of its jobs meet the leader's receives one
        // by one, and while the leader makes its own job the workers make theirs.
        constexpr size_t kPiece = size_t(1) << 30;
        for (uint32_t i = 0; i < count; ++i)
        {
            const int owner = int(i % ranks_);
            if (rank_ == 0 && owner == 0)
                take(i, job(i));
            else if (rank_ == 0)
            {
                uint64_t size = 0;
                check(MPI_Recv(&size, 1, MPI_UINT64_T, owner, kJob, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
                      "MPI_Recv");
                std::vector<std::byte> bytes(static_cast<size_t>(size));
                for (size_t at = 0; at < bytes.size(); at += kPiece)
                    check(MPI_Recv(bytes.data() + at, int(std::min(kPiece, bytes.size() - at)), MPI_BYTE,
                                   owner, kJob, MPI_COMM_WORLD, MPI_STATUS_IGNORE),
                          "MPI_Recv");
                take(i, std::move(bytes));
            }
            else if (int(rank_) == owner)
            {
                const std::vector<std::byte> bytes = job(i);
                const uint64_t size = bytes.size();
                check(MPI_Send(&size, 1, MPI_UINT64_T, 0, kJob, MPI_COMM_WORLD), "MPI_Send");
                for (size_t at = 0; at < bytes.size(); at += kPiece)
                    check(MPI_Send(bytes.data() + at, int(std::min(kPiece, bytes.size() - at)), MPI_BYTE, 0,
                                   kJob, MPI_COMM_WORLD),
                          "MPI_Send");
            }
        }
    }

  private:
    template <class Range>
    void lead(uint32_t slices, const Range& range, std::span<const bake::ItemArray> arrays,
              const std::function<void(uint32_t, uint32_t)>& compute,
              const std::function<void(uint32_t)>& finished)
    {
        std::vector<uint8_t> done(slices, 0), stopped(ranks_, 0);
        uint32_t next = 0, prefix = 0, completed = 0;
        const auto assign = [&](int worker)
        {
            int64_t s = next < slices ? int64_t(next++) : -1;
            if (s < 0)
            {
                if (stopped[size_t(worker)])
                    return;
                stopped[size_t(worker)] = 1;
            }
            check(MPI_Send(&s, 1, MPI_INT64_T, worker, kAssign, MPI_COMM_WORLD), "MPI_Send");
        };
        const auto mark = [&](uint32_t s)
        {
            done[s] = 1;
            ++completed;
            const uint32_t before = prefix;
            while (prefix < slices && done[prefix])
                ++prefix;
            if (prefix != before && prefix < slices && finished)
                finished(range(prefix).first);
        };
        // Results are received without blocking: across machines (TCP) a large message moves only while its
        // sender is inside an MPI call, which a worker is not while it computes; rank 0 goes on with its own
        // slices meanwhile and takes each result when it has arrived.
        struct Incoming
        {
            std::vector<std::byte> bytes;
            MPI_Request request = MPI_REQUEST_NULL;
            int source = 0;
        };
        std::list<Incoming> incoming;
        const auto take = [&](Incoming& in)
        {
            uint32_t s = 0;
            std::memcpy(&s, in.bytes.data(), 4);
            const auto [begin, end] = range(s);
            size_t at = 4;
            for (const bake::ItemArray& a : arrays)
            {
                const size_t bytes = size_t(end - begin) * a.item_bytes;
                std::memcpy(a.data + size_t(begin) * a.item_bytes, in.bytes.data() + at, bytes);
                at += bytes;
            }
            items_[size_t(in.source)] += end - begin;
            mark(s);
            assign(in.source);
        };
        // Starts receiving every result that has arrived (matched probes: each message is received by the
        // receive started for it), and takes those whose data is in.
        const auto poll = [&]
        {
            while (true)
            {
                int flag = 0;
                MPI_Message message;
                MPI_Status status;
                check(MPI_Improbe(MPI_ANY_SOURCE, kResult, MPI_COMM_WORLD, &flag, &message, &status),
                      "MPI_Improbe");
                if (!flag)
                    break;
                int count = 0;
                MPI_Get_count(&status, MPI_BYTE, &count);
                Incoming& in = incoming.emplace_back();
                in.bytes.resize(size_t(count));
                in.source = status.MPI_SOURCE;
                check(MPI_Imrecv(in.bytes.data(), count, MPI_BYTE, &message, &in.request), "MPI_Imrecv");
            }
            for (auto it = incoming.begin(); it != incoming.end();)
            {
                int arrived = 0;
                check(MPI_Test(&it->request, &arrived, MPI_STATUS_IGNORE), "MPI_Test");
                if (arrived)
                {
                    take(*it);
                    it = incoming.erase(it);
                }
                else
                    ++it;
            }
        };
        // Up to three slices in every worker's hand, so that it goes on with the next while its results wait
        // for rank 0; fewer when the pass has few slices, so that rank 0 keeps its share.
        const uint32_t ahead = std::clamp(slices / ranks_, 1u, uint32_t(kInHand));
        for (uint32_t round = 0; round < ahead; ++round)
            for (uint32_t w = 1; w < ranks_; ++w)
                if (next + 1 < slices) // the last slice stays with rank 0
                    assign(int(w));
        while (completed < slices)
        {
            poll();
            if (completed == slices)
                break;
            if (next < slices)
            {
                const uint32_t s = next++;
                const auto [begin, end] = range(s);
                compute(begin, end);
                items_[0] += end - begin;
                mark(s);
            }
            else if (!incoming.empty())
            {
                // Nothing left to compute here: wait for the oldest result on its way.
                check(MPI_Wait(&incoming.front().request, MPI_STATUS_IGNORE), "MPI_Wait");
                take(incoming.front());
                incoming.pop_front();
            }
            else
            {
                MPI_Status status;
                check(MPI_Probe(MPI_ANY_SOURCE, kResult, MPI_COMM_WORLD, &status), "MPI_Probe");
            }
        }
        // A worker that never got a slice (a pass of few slices) has not been told to stop yet.
        for (uint32_t w = 1; w < ranks_; ++w)
            assign(int(w));
    }

    template <class Range>
    void work(const Range& range, std::span<const bake::ItemArray> arrays,
              const std::function<void(uint32_t, uint32_t)>& compute)
    {
        // Results go out without waiting for rank 0 to take them (it does between its own slices): two
        // buffers in turn, the older send finished before its buffer is filled again.
        std::vector<std::byte> buffers[2];
        MPI_Request sent[2] = {MPI_REQUEST_NULL, MPI_REQUEST_NULL};
        for (int turn = 0;; turn ^= 1)
        {
            int64_t s = -1;
            check(MPI_Recv(&s, 1, MPI_INT64_T, 0, kAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "MPI_Recv");
            if (s < 0)
                break;
            const auto [begin, end] = range(uint32_t(s));
            compute(begin, end);
            check(MPI_Wait(&sent[turn], MPI_STATUS_IGNORE), "MPI_Wait");
            std::vector<std::byte>& buffer = buffers[turn];
            size_t bytes = 4;
            for (const bake::ItemArray& a : arrays)
                bytes += size_t(end - begin) * a.item_bytes;
            buffer.resize(bytes);
            const uint32_t index = uint32_t(s);
            std::memcpy(buffer.data(), &index, 4);
            size_t at = 4;
            for (const bake::ItemArray& a : arrays)
            {
                const size_t n = size_t(end - begin) * a.item_bytes;
                std::memcpy(buffer.data() + at, a.data + size_t(begin) * a.item_bytes, n);
                at += n;
            }
            check(MPI_Isend(buffer.data(), int(bytes), MPI_BYTE, 0, kResult, MPI_COMM_WORLD, &sent[turn]),
                  "MPI_Isend");
        }
        check(MPI_Waitall(2, sent, MPI_STATUSES_IGNORE), "MPI_Waitall");
    }

    std::vector<uint64_t> items_by_rank() const override { return items_; }

    uint32_t rank_ = 0, ranks_ = 1;
    std::vector<uint64_t> items_; // on the leader, per rank
};

// Whether a launcher started this process as a rank of a job: Open MPI's mpirun, or a PMIx/PMI one (srun).
bool launched_as_rank()
{
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
        if (std::getenv(name))
            return true;
    return false;
}

} // namespace

std::unique_ptr<MpiJob> join_mpi_job(int& argc, char**& argv)
{
    if (!launched_as_rank())
        return nullptr;
    return std::make_unique<Job>(argc, argv);
}

} // namespace hemi::tool
