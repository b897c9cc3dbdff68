#include <hemi/bake/checkpoint.h>
#include <hemi/bake/distribution.h>

#include <hemi/io/asset.h>
#include <hemi/io/atomic_file.h>
#include <hemi/io/image.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace hemi::bake
{

struct CheckpointKey::State
{
    XXH64_state_t xxh;
};

CheckpointKey::CheckpointKey(uint64_t version) : state_(std::make_unique<State>())
{
    XXH64_reset(&state_->xxh, version);
}

CheckpointKey::~CheckpointKey() = default;

CheckpointKey& CheckpointKey::add(std::span<const std::byte> bytes)
{
    XXH64_update(&state_->xxh, bytes.data(), bytes.size());
    return *this;
}

uint64_t CheckpointKey::digest() const
{
    return XXH64_digest(&state_->xxh);
}

namespace
{

constexpr size_t kMaxSectionName = 26; // io::AssetWriter's 31 bytes, less "ckpt."

std::string section_name(const std::string& name)
{
    return "ckpt." + name;
}

} // namespace

SliceCheckpoint::SliceCheckpoint(std::filesystem::path path, uint64_t key, uint32_t passes, uint32_t items,
                                 std::vector<CheckpointSection> sections, double interval_seconds)
    : path_(std::move(path)), key_(key), passes_(passes), items_(items), sections_(std::move(sections)),
      interval_(interval_seconds), active_(!path_.empty()), last_save_(std::chrono::steady_clock::now())
{
    if (passes_ == 0 || items_ == 0)
        throw std::invalid_argument("hemi: a checkpointed bake needs at least one pass and one item");
    for (size_t i = 0; i < sections_.size(); ++i)
    {
        const std::string& name = sections_[i].name;
        if (name.empty() || name.size() > kMaxSectionName || name == "key" || name == "state")
            throw std::invalid_argument("hemi: checkpoint section name '" + name +
                                        "' is empty, longer than " + std::to_string(kMaxSectionName) +
                                        " bytes or reserved");
        for (size_t j = 0; j < i; ++j)
            if (sections_[j].name == name)
                throw std::invalid_argument("hemi: checkpoint section '" + name + "' given twice");
    }
}

std::optional<SlicePosition> SliceCheckpoint::resume()
{
    std::optional<SlicePosition> found = load();
    // Reading a large checkpoint takes time of its own: the interval is one of baking.
    last_save_ = std::chrono::steady_clock::now();
    return found;
}

std::optional<SlicePosition> SliceCheckpoint::resume(Distribution& distribution)
{
    std::optional<SlicePosition> found = distribution.leader() ? resume() : std::nullopt;
    if (distribution.ranks() == 1)
        return found;
    uint8_t resumed = found.has_value();
    distribution.broadcast(std::as_writable_bytes(std::span<uint8_t>(&resumed, 1)));
    if (!resumed)
        return std::nullopt;
    SlicePosition position = found.value_or(SlicePosition{});
    distribution.broadcast(std::as_writable_bytes(std::span<SlicePosition>(&position, 1)));
    for (const CheckpointSection& section : sections_)
        distribution.broadcast(section.bytes);
    return position;
}

std::optional<SlicePosition> SliceCheckpoint::load()
{
    if (path_.empty() || !std::filesystem::exists(path_))
        return std::nullopt;
    try
    {
        const io::AssetReader r(path_);
        const std::vector<uint64_t> stored = r.array<uint64_t>("ckpt.key");
        const std::span<const std::byte> s = r.section("ckpt.state");
        if (stored.size() != 1 || stored[0] != key_ || s.size() != sizeof(SlicePosition))
            return std::nullopt;
        SlicePosition loaded;
        std::memcpy(&loaded, s.data(), sizeof loaded);
        std::vector<std::span<const std::byte>> saved;
        for (const CheckpointSection& section : sections_)
        {
            saved.push_back(r.section(section_name(section.name)));
            if (saved.back().size() != section.bytes.size())
                return std::nullopt;
        }
        // Only positions slice_done saves: inside the bake, never at its very start or past its end, or the
        // bake complete ({passes, 0}, saved with `now`).
        const bool complete = loaded.pass == passes_ && loaded.next_item == 0;
        if (!complete && (loaded.pass >= passes_ || loaded.next_item >= items_ ||
                          (loaded.pass == 0 && loaded.next_item == 0)))
            return std::nullopt;
        // Everything checked: only now is the bake's state overwritten.
        for (size_t i = 0; i < sections_.size(); ++i)
            if (!saved[i].empty())
                std::memcpy(sections_[i].bytes.data(), saved[i].data(), saved[i].size());
        return loaded;
    }
    catch (const io::FormatError&)
    {
        return std::nullopt;
    }
}

bool SliceCheckpoint::slice_done(uint32_t pass, uint32_t next_item, bool now)
{
    const bool complete = next_item >= items_ && pass + 1 >= passes_;
    if (!active_ || (complete && !now) ||
        (!now &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - last_save_).count() < interval_))
        return false;
    const SlicePosition position =
        next_item < items_ ? SlicePosition{pass, next_item} : SlicePosition{pass + 1, 0};
    bool saved = false;
    try
    {
        save(position);
        saved = true;
        // For tests of a killed job (docs/testing.md): HEMI_TEST_KILL_AFTER_PASS=N kills this process, as a
        // machine failure would, once a saved checkpoint stands in pass N or later.
        if (const char* kill_after = std::getenv("HEMI_TEST_KILL_AFTER_PASS"))
        {
            char* end = nullptr;
            const long n = std::strtol(kill_after, &end, 10);
            if (end != kill_after && *end == '\0' && n >= 0 && position.pass >= uint64_t(n))
                std::raise(SIGKILL);
        }
    }
    catch (const std::exception& e)
    {
        // A full disk or a lost folder must not cost the bake itself: it goes on, without further
        // checkpoints.
        error_ = e.what();
        active_ = false;
    }
    last_save_ = std::chrono::steady_clock::now();
    return saved;
}

void SliceCheckpoint::save(const SlicePosition& position) const
{
    io::AssetWriter w;
    w.add_array<uint64_t>("ckpt.key", std::span<const uint64_t>(&key_, 1));
    w.add("ckpt.state", std::as_bytes(std::span<const SlicePosition>(&position, 1)));
    // The arrays are written from where they are: a checkpoint of a large bake makes no copy of its state.
    for (const CheckpointSection& section : sections_)
        w.add_view(section_name(section.name), section.bytes);
    w.write(path_);
}

std::filesystem::path checkpoint_path(const std::filesystem::path& asset)
{
    return asset.string() + ".partial";
}

void remove_checkpoint(const std::filesystem::path& path) noexcept
{
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    // And what a checkpoint write killed before its rename left beside it (io::write_atomically's
    // temporaries): a finished bake leaves no trace of its checkpoints.
    try
    {
        for (const std::filesystem::path& stale : io::stale_temporaries(path))
            std::filesystem::remove(stale, ignored);
    }
    catch (...)
    {
        // best effort, like the checkpoint itself
    }
}

} // namespace hemi::bake
