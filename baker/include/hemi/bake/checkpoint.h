#pragma once
// Checkpoints of a long bake, so that an interrupted one (a crash, a kill, a full queue's time limit) loses
// at most a few seconds of work instead of all of it.
//
// The bakes it fits process `items` items (vertices, texels) in `passes` passes, pass by pass and slice by
// slice, each slice a range of items in order; and everything they have finished lives in a few byte arrays
// of their own ("sections") that they update in place. Between slices the bake tells the checkpoint how far
// it got; at most every `interval` seconds the checkpoint then saves the sections and that position to its
// file (ASSET.partial beside the asset, by default), atomically: a crash while saving leaves the previous
// checkpoint whole. Started again, the bake asks the checkpoint to resume: when the file holds the same key
// (a hash of everything the result depends on: the scene, every option that changes a number, the layout)
// and the same section sizes, the sections are restored and the bake goes on from the saved position. Given
// that an item's result depends only on the key and on the finished state, the resumed bake gives the same
// bytes as an uninterrupted one. A file of another key or layout, or a damaged one, is ignored (and replaced
// by the next save). The bake never removes the file: its caller does, once the final result is written
// (remove_checkpoint), since until then the checkpoint is the only copy of the work.
//
// The file is a hemi asset container (io::AssetWriter): "ckpt.key" (u64), "ckpt.state" (SlicePosition), then
// "ckpt.<name>" for each section, in the order given.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace hemi::bake
{

class Distribution;

// Where a bake stands: passes before `pass` are complete, and so are items [0, next_item) of `pass`.
struct SlicePosition
{
    uint32_t pass = 0;
    uint32_t next_item = 0;
    bool operator==(const SlicePosition&) const = default;
};

// One of the arrays a bake's finished state lives in. The bake keeps the storage (and does not resize it)
// for as long as the checkpoint may save from it or resume into it.
struct CheckpointSection
{
    std::string name;           // in the file as "ckpt." + name: at most 26 bytes
    std::span<std::byte> bytes; // saved from here, restored into here
};

// The key of a checkpoint: XXH64 over the bytes added, in order, seeded with the bake's checkpoint format
// version (bump it when the sections change meaning, so old files are ignored rather than misread).
class CheckpointKey
{
  public:
    explicit CheckpointKey(uint64_t version);
    ~CheckpointKey();
    CheckpointKey(const CheckpointKey&) = delete;
    CheckpointKey& operator=(const CheckpointKey&) = delete;

    CheckpointKey& add(std::span<const std::byte> bytes);
    template <typename T> CheckpointKey& add_array(std::span<const T> values)
    {
        return add(std::as_bytes(values));
    }
    template <typename T> CheckpointKey& add_value(const T& value)
    {
        return add(std::as_bytes(std::span<const T>(&value, 1)));
    }
    uint64_t digest() const;

  private:
    struct State;
    std::unique_ptr<State> state_;
};

class SliceCheckpoint
{
  public:
    // An empty `path` makes a checkpoint that is off: resume() finds nothing and nothing is saved.
    // `interval_seconds` 0 (or less) saves after every slice. Throws std::invalid_argument for passes or
    // items of 0, or a section name that is empty, too long, repeated or "key" or "state".
    SliceCheckpoint(std::filesystem::path path, uint64_t key, uint32_t passes, uint32_t items,
                    std::vector<CheckpointSection> sections, double interval_seconds);

    // Restores the state saved for this key into the sections and returns where to go on from; std::nullopt,
    // with no section touched, when there is no file, or it is unreadable or damaged, or it holds another
    // key, other section sizes or a position that save never writes (the very start, or past the end other
    // than {passes, 0}: the bake complete, which slice_done(..., now) saves). The
    // interval to the first save counts from here (or from construction when the bake does not resume).
    std::optional<SlicePosition> resume();
    // resume() for the ranks of a job (distribution.h): the leader resumes from its file, and the other ranks
    // (whose checkpoints are off) receive the position and every section it restored, so that all go on from
    // the same state. Returns the same on every rank.
    std::optional<SlicePosition> resume(Distribution& distribution);

    // Call between slices, with the bake's position: `pass` has finished items [0, next_item), next_item ==
    // items meaning the pass is complete. Saves when the checkpoint is on, the bake is not complete and
    // `interval_seconds` have passed since the last save (or resume). A failed save turns checkpointing off
    // and error() says why: a checkpoint is insurance, not the result, and the bake goes on without it.
    // Returns whether it saved. `now` saves whatever the interval, and also when the bake is complete (as
    // {passes, 0}): a bake whose state outside the sections must not run more than a pass ahead of its
    // checkpoint (the tile file of texel_file.h), and whose work after the last pass overwrites what a
    // resumed last pass would read (the denoiser's filter in the tile file's other copy).
    bool slice_done(uint32_t pass, uint32_t next_item, bool now = false);

    // Saves the sections and `position` now (atomically: temporary file, then rename). Throws
    // io::FormatError naming the file when writing fails; the previous checkpoint is then left as it was.
    void save(const SlicePosition& position) const;

    bool active() const { return active_; }
    const std::string& error() const { return error_; }
    const std::filesystem::path& path() const { return path_; }

  private:
    std::optional<SlicePosition> load();

    std::filesystem::path path_;
    uint64_t key_;
    uint32_t passes_, items_;
    std::vector<CheckpointSection> sections_;
    double interval_;
    bool active_;
    std::string error_;
    std::chrono::steady_clock::time_point last_save_;
};

// ASSET.partial: where the bake of `asset` checkpoints unless told otherwise.
std::filesystem::path checkpoint_path(const std::filesystem::path& asset);

// Removes a checkpoint once the result it was insurance for is written, with the temporaries of checkpoint
// writes that were killed before their rename; no file is fine, and a failure is
// ignored (a stale checkpoint is harmless: its key no longer matches anything, or it resumes to the same
// bytes).
void remove_checkpoint(const std::filesystem::path& path) noexcept;

} // namespace hemi::bake
