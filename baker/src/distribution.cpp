#include <hemi/bake/distribution.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hemi::bake
{

namespace
{
class Local final : public Distribution
{
  public:
    uint32_t rank() const override { return 0; }
    uint32_t ranks() const override { return 1; }
    void run(uint32_t first, uint32_t items, uint32_t slice, std::span<const ItemArray>,
             const std::function<void(uint32_t, uint32_t)>& compute,
             const std::function<void(uint32_t)>& finished) override
    {
        for (uint32_t begin = first; begin < items;)
        {
            const uint32_t end = std::min(items, begin + std::max(slice, 1u));
            compute(begin, end);
            items_ += end - begin;
            begin = end;
            if (end < items && finished)
                finished(end);
        }
    }
    void broadcast(std::span<std::byte>) override {}
    std::vector<uint64_t> items_by_rank() const override { return {items_}; }

  private:
    uint64_t items_ = 0;
};
} // namespace

void Distribution::check_same(uint64_t value, const std::string& what)
{
    if (ranks() == 1)
        return;
    uint64_t leaders = value;
    broadcast(std::as_writable_bytes(std::span<uint64_t>(&leaders, 1)));
    if (leaders != value)
        throw std::runtime_error("rank " + std::to_string(rank()) + " " + what +
                                 " differs from rank 0's: every rank needs the same hemi-bake and the same "
                                 "inputs at the same paths");
}

Distribution& local_distribution()
{
    static Local local;
    return local;
}

} // namespace hemi::bake
