// Sizes as people write them (io/memory.h): what --memory-budget and HEMI_MEMORY_BUDGET take, and what they
// refuse instead of reading part of it (strtod would take " 8G", "0x100000", "8e9" and "inf", and a unit
// followed by anything).
#include <hemi/io/memory.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

TEST(Memory, SizesAreReadWholeOrNotAtAll)
{
    EXPECT_EQ(hemi::io::parse_bytes("4096"), 4096u);
    EXPECT_EQ(hemi::io::parse_bytes("4096B"), 4096u);
    EXPECT_EQ(hemi::io::parse_bytes("8G"), uint64_t(8) << 30);
    EXPECT_EQ(hemi::io::parse_bytes("8g"), uint64_t(8) << 30);
    EXPECT_EQ(hemi::io::parse_bytes("8GB"), uint64_t(8) << 30);
    EXPECT_EQ(hemi::io::parse_bytes("1.5GiB"), uint64_t(3) << 29);
    EXPECT_EQ(hemi::io::parse_bytes("512M"), uint64_t(512) << 20);
    EXPECT_EQ(hemi::io::parse_bytes("2T"), uint64_t(2) << 40);
    EXPECT_EQ(hemi::io::parse_bytes("64K"), uint64_t(64) << 10);
    for (const char* bad :
         {"",    "lots", "8GBB", "64MBB", "0x100000", " 8G", "8G ", "8 G", "-1",    "+8G", "0",
          "0.5", "8e9",  "inf",  "nan",   "4Gb",      "8iB", "1.",  ".5G", "8GiBB", "8X",  "1e30"})
        EXPECT_EQ(hemi::io::parse_bytes(bad), 0u) << "'" << bad << "'";
}

// HEMI_MEMORY_BUDGET that is not a size is refused by name, not ignored (the budget would be all the machine
// has); a size lowers what is available to it.
TEST(Memory, AMemoryBudgetInTheEnvironmentThatIsNotASizeIsRefused)
{
    const char* before = std::getenv("HEMI_MEMORY_BUDGET");
    const std::string saved = before ? before : "";
    for (const char* bad : {"4Gb", "abc", "-1", "0"})
    {
        setenv("HEMI_MEMORY_BUDGET", bad, 1);
        try
        {
            (void)hemi::io::available_memory();
            ADD_FAILURE() << "HEMI_MEMORY_BUDGET=" << bad << " accepted";
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(std::string("HEMI_MEMORY_BUDGET=") + bad + ": not a size"),
                      std::string::npos)
                << e.what();
        }
    }
    setenv("HEMI_MEMORY_BUDGET", "3M", 1);
    EXPECT_LE(hemi::io::available_memory(), uint64_t(3) << 20);
    EXPECT_GT(hemi::io::available_memory(), 0u);
    if (before)
        setenv("HEMI_MEMORY_BUDGET", saved.c_str(), 1);
    else
        unsetenv("HEMI_MEMORY_BUDGET");
}
