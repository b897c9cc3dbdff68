// Checkpoints of sliced bakes, on a toy bake of the kind they serve (passes over items in slices, state in
// a few arrays): interrupted anywhere and resumed it gives the bytes of an uninterrupted run; saves come at
// most every interval and never after the end; a file of another key or layout, a damaged or foreign one,
// or one at a position no save writes is ignored without touching the bake's state; a save that fails or a
// process killed in the middle of one leaves the previous checkpoint whole.
#include "../temp_dir.h"

#include <hemi/bake/checkpoint.h>
#include <hemi/io/asset.h>

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <span>
#include <vector>

namespace
{

namespace fs = std::filesystem;
using hemi::bake::CheckpointSection;
using hemi::bake::SliceCheckpoint;
using hemi::bake::SlicePosition;

fs::path dir()
{
    static const fs::path d = hemi::test::temp_dir("checkpoint_test");
    return d;
}

struct Interrupt
{
};

constexpr uint32_t kItems = 1000, kPasses = 3, kSlice = 128; // 8 slices a pass, the last one short

struct ToyResult
{
    std::vector<double> value;
    std::optional<SlicePosition> resumed;
    int saves = 0;
};

// A toy bake: pass p adds to each item a number of its own plus half of another item's value at the end of
// pass p - 1, so a resumed run is right only if all of its state (this pass's values and the previous
// pass's) comes back. Stops with Interrupt after `stop_after` slices (0: never).
ToyResult toy_bake(const fs::path& path, uint64_t key, double interval, int stop_after)
{
    ToyResult out;
    out.value.assign(kItems, 0.0);
    std::vector<double> previous(kItems, 0.0);
    SliceCheckpoint checkpoint(path, key, kPasses, kItems,
                               {{"value", std::as_writable_bytes(std::span<double>(out.value))},
                                {"previous", std::as_writable_bytes(std::span<double>(previous))}},
                               interval);
    out.resumed = checkpoint.resume();
    const SlicePosition at = out.resumed.value_or(SlicePosition{});
    int slices = 0;
    for (uint32_t pass = at.pass; pass < kPasses; ++pass)
    {
        const bool mid_pass = pass == at.pass && at.next_item > 0;
        if (!mid_pass)
            std::copy(out.value.begin(), out.value.end(), previous.begin());
        for (uint32_t first = mid_pass ? at.next_item : 0; first < kItems;)
        {
            const uint32_t last = std::min(kItems, first + kSlice);
            for (uint32_t i = first; i < last; ++i)
                out.value[i] += std::sin(double(i) + pass) + 0.5 * previous[(i * 7 + 3) % kItems];
            first = last;
            out.saves += checkpoint.slice_done(pass, first);
            if (++slices == stop_after)
                throw Interrupt{};
        }
    }
    return out;
}

bool same_bytes(const std::vector<double>& a, const std::vector<double>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// The temporaries io::write_atomically leaves beside `path` when its process dies before the rename.
std::vector<fs::path> temporaries(const fs::path& path)
{
    std::vector<fs::path> out;
    for (const fs::directory_entry& e : fs::directory_iterator(path.parent_path()))
        if (e.path().filename().string().rfind(path.filename().string() + ".tmp", 0) == 0)
            out.push_back(e.path());
    return out;
}

// The file-size limit the save tests run their writer under: a quarter of a Blob's checkpoint.
constexpr rlim_t kLimit = 16 * 1024;

// A checkpoint of one 64 KiB section, every byte `fill`, saved at {0, 5} of 1 pass over 10 items.
struct Blob
{
    std::vector<std::byte> bytes = std::vector<std::byte>(64 * 1024);
    SliceCheckpoint checkpoint;
    Blob(const fs::path& path, uint8_t fill)
        : checkpoint(path, 42, 1, 10, {{"blob", std::span<std::byte>(bytes)}}, 0.0)
    {
        std::fill(bytes.begin(), bytes.end(), std::byte(fill));
    }
};

} // namespace

TEST(Checkpoint, InterruptedAnywhereResumesToTheSameBytes)
{
    const std::vector<double> whole = toy_bake({}, 1, 0.0, 0).value;
    const fs::path path = dir() / "toy.partial";
    // 24 slices in all: mid-pass 0, the end of pass 0 (saved as the start of pass 1), mid-pass 1, the last
    // slice but one.
    const std::pair<int, SlicePosition> stops[] = {
        {1, {0, 128}}, {8, {1, 0}}, {11, {1, 384}}, {23, {2, 896}}};
    for (const auto& [stop, position] : stops)
    {
        fs::remove(path);
        EXPECT_THROW(toy_bake(path, 1, 0.0, stop), Interrupt);
        const ToyResult resumed = toy_bake(path, 1, 0.0, 0);
        ASSERT_TRUE(resumed.resumed.has_value()) << stop;
        EXPECT_EQ(*resumed.resumed, position) << stop;
        EXPECT_TRUE(same_bytes(resumed.value, whole)) << "stopped after slice " << stop;
        // The resumed run saves its own slices, but not the last (the bake is complete then), and it leaves
        // the file for the caller to remove once the result is safe.
        EXPECT_EQ(resumed.saves, 24 - stop - 1) << stop;
        EXPECT_TRUE(fs::exists(path));
    }
    hemi::bake::remove_checkpoint(path);
    EXPECT_FALSE(fs::exists(path));
    hemi::bake::remove_checkpoint(path); // no file: fine
    EXPECT_EQ(hemi::bake::checkpoint_path(dir() / "scene.hemi"), dir() / "scene.hemi.partial");
}

TEST(Checkpoint, SavesAtMostEveryIntervalAndNeverAtTheEnd)
{
    const fs::path path = dir() / "interval.partial";
    fs::remove(path);
    // An hour between saves: a bake of seconds saves nothing.
    EXPECT_THROW(toy_bake(path, 1, 3600.0, 20), Interrupt);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_EQ(toy_bake(path, 1, 3600.0, 0).saves, 0);
    // Every slice but the very last.
    EXPECT_EQ(toy_bake(path, 1, 0.0, 0).saves, 23);

    std::vector<float> state(4, 1.0f);
    SliceCheckpoint c(path, 7, 2, 4, {{"values", std::as_writable_bytes(std::span<float>(state))}}, 0.0);
    EXPECT_TRUE(c.active());
    EXPECT_TRUE(c.slice_done(0, 2));
    EXPECT_TRUE(c.slice_done(0, 4)); // pass 0 complete: saved as the start of pass 1
    std::vector<float> restored(4, 0.0f);
    SliceCheckpoint r(path, 7, 2, 4, {{"values", std::as_writable_bytes(std::span<float>(restored))}}, 0.0);
    EXPECT_EQ(r.resume(), (SlicePosition{1, 0}));
    EXPECT_EQ(restored, state);
    EXPECT_TRUE(c.slice_done(1, 3));
    EXPECT_FALSE(c.slice_done(1, 4)) << "the bake is complete: its result, not a checkpoint, is next";
    EXPECT_EQ(r.resume(), (SlicePosition{1, 3}));

    // Off: an empty path resumes nothing and saves nothing.
    SliceCheckpoint off({}, 7, 2, 4, {{"values", std::as_writable_bytes(std::span<float>(state))}}, 0.0);
    EXPECT_FALSE(off.active());
    EXPECT_FALSE(off.resume().has_value());
    EXPECT_FALSE(off.slice_done(0, 1));
    fs::remove(path);
}

// What resume ignores, leaving every byte of the bake's state as it was.
TEST(Checkpoint, IgnoresOtherKeysLayoutsPositionsAndDamagedFiles)
{
    const fs::path path = dir() / "ignored.partial";
    std::vector<uint32_t> saved(16, 5u);
    SliceCheckpoint writer(path, 100, 2, 16, {{"a", std::as_writable_bytes(std::span<uint32_t>(saved))}},
                           0.0);
    writer.save({1, 3});

    std::vector<uint32_t> state(16, 9u), wide(17, 9u);
    const auto untouched = [&]
    { return std::all_of(state.begin(), state.end(), [](uint32_t v) { return v == 9u; }); };
    const auto resume =
        [&](uint64_t key, uint32_t passes, uint32_t items, std::vector<CheckpointSection> sections)
    { return SliceCheckpoint(path, key, passes, items, std::move(sections), 0.0).resume(); };
    const std::span<std::byte> bytes = std::as_writable_bytes(std::span<uint32_t>(state));
    // The same bake resumes (checked first, so that the refusals below are the checkpoint's doing).
    {
        std::vector<uint32_t> copy(16, 0u);
        EXPECT_EQ(resume(100, 2, 16, {{"a", std::as_writable_bytes(std::span<uint32_t>(copy))}}),
                  (SlicePosition{1, 3}));
        EXPECT_EQ(copy, saved);
    }
    EXPECT_FALSE(resume(101, 2, 16, {{"a", bytes}})) << "another key";
    EXPECT_FALSE(resume(100, 2, 16, {{"a", std::as_writable_bytes(std::span<uint32_t>(wide))}}))
        << "another size";
    EXPECT_FALSE(resume(100, 2, 16, {{"b", bytes}})) << "a section the file lacks";
    EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}, {"b", bytes.subspan(0, 4)}})) << "one section more";
    EXPECT_FALSE(resume(100, 1, 16, {{"a", bytes}})) << "pass 1 of a one-pass bake";
    EXPECT_FALSE(resume(100, 2, 3, {{"a", bytes}})) << "item 3 of 3";
    EXPECT_TRUE(untouched());

    // Positions no save writes: the very start, and past the end (other than the bake complete).
    for (const SlicePosition p :
         {SlicePosition{0, 0}, SlicePosition{3, 0}, SlicePosition{2, 1}, SlicePosition{0, 16}})
    {
        writer.save(p);
        EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}})) << p.pass << " " << p.next_item;
    }
    EXPECT_TRUE(untouched());
    // The bake complete, {passes, 0}: what slice_done(..., now) saves after the last pass (issue 41).
    {
        SliceCheckpoint complete(path, 100, 2, 16,
                                 {{"a", std::as_writable_bytes(std::span<uint32_t>(saved))}}, 1e9);
        EXPECT_FALSE(complete.slice_done(1, 16)) << "not forced: the result, not a checkpoint, is next";
        EXPECT_TRUE(complete.slice_done(1, 16, true));
        std::vector<uint32_t> copy(16, 0u);
        EXPECT_EQ(resume(100, 2, 16, {{"a", std::as_writable_bytes(std::span<uint32_t>(copy))}}),
                  (SlicePosition{2, 0}));
        EXPECT_EQ(copy, saved);
    }

    // Damaged: one byte changed, cut short, not a hemi container, or a container of something else.
    writer.save({1, 3});
    {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(120);
        f.put('\x7f');
    }
    EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}})) << "corrupted";
    writer.save({1, 3});
    fs::resize_file(path, fs::file_size(path) - 9);
    EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}})) << "truncated";
    std::ofstream(path, std::ios::binary) << "not a checkpoint at all";
    EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}})) << "garbage";
    hemi::io::AssetWriter other;
    other.add("mesh.positions", std::as_bytes(std::span<uint32_t>(saved)));
    other.write(path);
    EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}})) << "an asset, not a checkpoint";
    fs::remove(path);
    EXPECT_FALSE(resume(100, 2, 16, {{"a", bytes}})) << "no file";
    EXPECT_TRUE(untouched());
}

TEST(Checkpoint, RejectsBadLayouts)
{
    std::vector<std::byte> b(8);
    const std::span<std::byte> s(b);
    const fs::path path = dir() / "bad.partial";
    EXPECT_THROW(SliceCheckpoint(path, 1, 0, 4, {{"a", s}}, 0.0), std::invalid_argument);
    EXPECT_THROW(SliceCheckpoint(path, 1, 1, 0, {{"a", s}}, 0.0), std::invalid_argument);
    EXPECT_THROW(SliceCheckpoint(path, 1, 1, 4, {{"", s}}, 0.0), std::invalid_argument);
    EXPECT_THROW(SliceCheckpoint(path, 1, 1, 4, {{std::string(27, 'x'), s}}, 0.0), std::invalid_argument);
    EXPECT_NO_THROW(SliceCheckpoint(path, 1, 1, 4, {{std::string(26, 'x'), s}}, 0.0));
    EXPECT_THROW(SliceCheckpoint(path, 1, 1, 4, {{"a", s}, {"a", s}}, 0.0), std::invalid_argument);
    EXPECT_THROW(SliceCheckpoint(path, 1, 1, 4, {{"key", s}}, 0.0), std::invalid_argument);
    EXPECT_THROW(SliceCheckpoint(path, 1, 1, 4, {{"state", s}}, 0.0), std::invalid_argument);
}

// A save that fails (here: the file-size limit, as a full disk would) leaves the previous checkpoint whole,
// removes its temporary, and turns checkpointing off with the reason; the bake is told, not stopped.
TEST(Checkpoint, FailedSaveKeepsThePreviousCheckpoint)
{
    const fs::path path = dir() / "failed.partial";
    {
        Blob old(path, 0x11);
        old.checkpoint.save({0, 5});
    }
    Blob next(path, 0x22);
    const auto child = [&]
    {
        std::signal(SIGXFSZ, SIG_IGN); // writes past the limit fail with EFBIG instead of killing
        const rlimit limit{kLimit, kLimit};
        setrlimit(RLIMIT_FSIZE, &limit);
        const bool saved = next.checkpoint.slice_done(0, 6);
        std::fprintf(stderr, "%s\n", next.checkpoint.error().c_str());
        std::_Exit(!saved && !next.checkpoint.active() ? 0 : 1);
    };
    EXPECT_EXIT(child(), testing::ExitedWithCode(0), "failed\\.partial.*File too large");
    EXPECT_TRUE(temporaries(path).empty());
    Blob back(path, 0);
    EXPECT_EQ(back.checkpoint.resume(), (SlicePosition{0, 5}));
    EXPECT_TRUE(
        std::all_of(back.bytes.begin(), back.bytes.end(), [](std::byte v) { return v == std::byte(0x11); }));
    fs::remove(path);
}

// A process killed in the middle of a save (SIGXFSZ at the file-size limit: mid-write, before the rename)
// leaves the previous checkpoint whole and resumable; its half-written temporary never stands in for it, and
// the next save clears it away.
TEST(Checkpoint, CrashBeforeRenameLeavesThePreviousCheckpoint)
{
    const fs::path path = dir() / "crash.partial";
    {
        Blob old(path, 0x11);
        old.checkpoint.save({0, 5});
    }
    const uintmax_t old_size = fs::file_size(path);
    Blob next(path, 0x22);
    const auto child = [&]
    {
        const rlimit no_core{0, 0}, limit{kLimit, kLimit};
        setrlimit(RLIMIT_CORE, &no_core);
        setrlimit(RLIMIT_FSIZE, &limit);
        next.checkpoint.save({0, 6});
        std::_Exit(0); // not reached
    };
    EXPECT_EXIT(child(), testing::KilledBySignal(SIGXFSZ), "");
    const std::vector<fs::path> left = temporaries(path);
    ASSERT_EQ(left.size(), 1u) << "the killed save should have left its half-written temporary";
    EXPECT_LE(fs::file_size(left[0]), kLimit);
    EXPECT_EQ(fs::file_size(path), old_size);
    {
        Blob back(path, 0);
        EXPECT_EQ(back.checkpoint.resume(), (SlicePosition{0, 5}));
        EXPECT_TRUE(std::all_of(back.bytes.begin(), back.bytes.end(),
                                [](std::byte v) { return v == std::byte(0x11); }));
    }
    next.checkpoint.save({0, 6});
    EXPECT_TRUE(temporaries(path).empty());
    Blob back(path, 0);
    EXPECT_EQ(back.checkpoint.resume(), (SlicePosition{0, 6}));
    EXPECT_TRUE(back.bytes == next.bytes);
    fs::remove(path);
}

// The key hashes the bytes added, in order, from the version: how they are split into calls does not matter
// (the PRT bake's keys stayed what they were when it hashed in one function).
TEST(Checkpoint, KeyDependsOnTheBytesInOrderAndOnTheVersion)
{
    const uint32_t a[3] = {1, 2, 3};
    const auto key = [&](uint64_t version, bool split, bool swapped)
    {
        hemi::bake::CheckpointKey k(version);
        if (swapped)
            k.add_value(a[1]).add_value(a[0]).add_value(a[2]);
        else if (split)
            k.add_value(a[0]).add_array<uint32_t>(std::span<const uint32_t>(a + 1, 2));
        else
            k.add_array<uint32_t>(a);
        return k.digest();
    };
    EXPECT_EQ(key(2, false, false), key(2, true, false));
    EXPECT_NE(key(2, false, false), key(2, false, true));
    EXPECT_NE(key(2, false, false), key(3, false, false));
    hemi::bake::CheckpointKey empty(2);
    EXPECT_EQ(empty.digest(), hemi::bake::CheckpointKey(2).digest());
}
