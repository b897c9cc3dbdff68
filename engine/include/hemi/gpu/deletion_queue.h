#pragma once
// Deferred destruction for engines with frames in flight: an object the GPU may still be reading (a model
// replaced, a material type dropped, a staging UploadBatch) is retired with the number of the frame that
// last used it, and destroyed by collect() once the engine knows that frame has finished (its fence
// signalled). hemi itself never waits on the engine's queue to destroy anything.
//
//     deletions.retire(frame, std::move(old_model));   // any movable object, e.g. a render::PrtModel
//     ...                                               // each frame, after waiting for frame F's fence:
//     deletions.collect(F);                             // destroys what frames <= F used
//
// Not thread-safe (one per render thread); the destructor destroys what is left (the engine waits idle
// first).

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <utility>

namespace hemi::gpu
{

class DeletionQueue
{
  public:
    DeletionQueue() = default;
    DeletionQueue(const DeletionQueue&) = delete;
    DeletionQueue& operator=(const DeletionQueue&) = delete;
    ~DeletionQueue() = default;

    // Keeps `object` alive until collect(f) with f >= `frame`. Frames are the engine's own counter.
    template <typename T> void retire(uint64_t frame, T&& object)
    {
        using Held = std::decay_t<T>;
        entries_.push_back({frame, std::shared_ptr<void>(new Held(std::forward<T>(object)),
                                                         [](void* p) { delete static_cast<Held*>(p); })});
    }

    // Destroys every object retired for a frame <= `completed_frame`, in the order retired.
    void collect(uint64_t completed_frame)
    {
        std::deque<Entry> keep;
        for (Entry& e : entries_)
            if (e.frame > completed_frame)
                keep.push_back(std::move(e));
        entries_.clear(); // destroys the collected ones, oldest first
        entries_ = std::move(keep);
    }

    size_t pending() const { return entries_.size(); }

  private:
    struct Entry
    {
        uint64_t frame;
        std::shared_ptr<void> object;
    };
    std::deque<Entry> entries_;
};

} // namespace hemi::gpu
