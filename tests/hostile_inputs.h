#pragma once
// Hostile inputs that once got through a reader, made in code: shared by the regression tests and the fuzz
// targets' regression corpora (tests/fuzz/fuzz_seeds.cpp).
#include <cstdint>
#include <cstring>
#include <iterator>
#include <string>
#include <vector>

namespace hemi::test
{

// `jpeg` with its first Huffman table (DHT) replaced by one of 272 codes, with 272 symbol bytes: a
// well-formed segment that Debian's stb_image builds into a 257-byte array (a write out of bounds, found by
// tests/fuzz/fuzz_image).
// `jpeg` with its first Huffman table (DHT) replaced by `counts` (16 code counts) and as many symbols.
inline std::vector<uint8_t> jpeg_with_huffman_table(const std::vector<uint8_t>& jpeg,
                                                    const uint8_t (&counts)[16])
{
    for (size_t at = 2; at + 4 < jpeg.size();)
    {
        if (jpeg[at] != 0xFF)
            break;
        const uint8_t marker = jpeg[at + 1];
        const size_t length = size_t(jpeg[at + 2]) << 8 | jpeg[at + 3];
        if (marker == 0xC4)
        {
            std::vector<uint8_t> table = {jpeg[at + 4]}; // class and id of the original first table
            size_t symbols = 0;
            for (uint8_t c : counts)
                table.push_back(c), symbols += c;
            for (size_t i = 0; i < symbols; ++i)
                table.push_back(uint8_t(i));
            std::vector<uint8_t> out(jpeg.begin(), jpeg.begin() + long(at));
            const size_t new_length = table.size() + 2;
            out.insert(out.end(), {0xFF, 0xC4, uint8_t(new_length >> 8), uint8_t(new_length & 0xFF)});
            out.insert(out.end(), table.begin(), table.end());
            out.insert(out.end(), jpeg.begin() + long(at + 2 + length), jpeg.end());
            return out;
        }
        if (marker == 0xDA)
            break;
        at += 2 + length;
    }
    return {};
}

// Three codes of length 1: no prefix code, and stb_image 2.27 indexes its tables with negative numbers
// (found by tests/fuzz/fuzz_image).
inline std::vector<uint8_t> jpeg_with_oversubscribed_huffman_table(const std::vector<uint8_t>& jpeg)
{
    const uint8_t counts[16] = {3};
    return jpeg_with_huffman_table(jpeg, counts);
}

inline std::vector<uint8_t> jpeg_with_oversized_huffman_table(const std::vector<uint8_t>& jpeg)
{
    // 17 codes of length 15 and 255 of length 16: 272 codes, a valid prefix code (Kraft sum 289 of 65536),
    // more than the 256 a table can hold.
    const uint8_t counts[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 17, 255};
    return jpeg_with_huffman_table(jpeg, counts);
}

// `jpeg` with its frame header claiming `width` x `height`: a few hundred bytes that a decoder trusting the
// header would spend seconds and gigabytes on (found by tests/fuzz/fuzz_image: 16392 x 9488 in 760 bytes).
inline std::vector<uint8_t> jpeg_with_frame_size(std::vector<uint8_t> jpeg, uint16_t width, uint16_t height)
{
    for (size_t at = 2; at + 9 < jpeg.size(); ++at)
        if (jpeg[at] == 0xFF && jpeg[at + 1] == 0xC0) // SOF0: length, precision, height, width
        {
            jpeg[at + 5] = uint8_t(height >> 8), jpeg[at + 6] = uint8_t(height);
            jpeg[at + 7] = uint8_t(width >> 8), jpeg[at + 8] = uint8_t(width);
            return jpeg;
        }
    return {};
}

// `jpeg` with its first scan's first component decoding with AC table 2, which no DHT defines: stb_image 2.27
// decodes with a zeroed table and reads its symbols out of bounds (found by tests/fuzz/fuzz_image's short
// campaign in CI).
inline std::vector<uint8_t> jpeg_with_undefined_huffman_table(std::vector<uint8_t> jpeg)
{
    for (size_t at = 2; at + 6 < jpeg.size(); ++at)
        if (jpeg[at] == 0xFF &&
            jpeg[at + 1] == 0xDA) // SOS: length, Ns, then (Cs, Td << 4 | Ta) per component
        {
            jpeg[at + 6] = uint8_t((jpeg[at + 6] & 0xF0) | 0x02);
            return jpeg;
        }
    return {};
}

// A baseline (sequential) JPEG whose scan says Se = 0 and gives its first component AC table 2, which no DHT
// defines: a sequential decoder reads AC coefficients anyway (the fuzzer found stb_image doing so).
inline std::vector<uint8_t> jpeg_with_undefined_ac_table_in_a_baseline_scan(std::vector<uint8_t> jpeg)
{
    for (size_t at = 2; at + 6 < jpeg.size(); ++at)
        if (jpeg[at] == 0xFF && jpeg[at + 1] == 0xDA)
        {
            const size_t components = jpeg[at + 4];
            if (at + 6 + 2 * components >= jpeg.size())
                return {};
            jpeg[at + 6] = uint8_t((jpeg[at + 6] & 0xF0) | 0x02);
            jpeg[at + 5 + 2 * components + 1] = 0; // Se
            return jpeg;
        }
    return {};
}

// The fuzz seed's JPEG (io::encode_jpeg(pattern(16, 8), 80) in tests/fuzz/fuzz_seeds.cpp, 722 bytes) as
// the fuzzer changed it: a Huffman table's symbols and the entropy-coded data damaged, fill bytes inserted.
// stb_image then shifted its bit buffer by 34 (undefined behaviour); libjpeg refuses it. Byte edits at
// offsets of the original ({offset, bytes erased, bytes inserted as hex}), applied from the last.
inline std::vector<uint8_t> jpeg_with_damaged_entropy_data(std::vector<uint8_t> jpeg)
{
    struct Edit
    {
        size_t offset, erase;
        const char* hex;
    };
    static const Edit edits[] = {
        {232, 1, "32"},
        {454, 4, "64616669"},
        {617, 0,
         "ffffffffffff00fefffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffffff"
         "fff"
         "ffffffffffffffffff"},
        {635, 1, "35"},
        {639, 45, ""},
        {689, 1, "fe"},
        {704, 2, "0981"},
    };
    if (jpeg.size() != 722)
        return {};
    for (size_t e = std::size(edits); e-- > 0;)
    {
        std::vector<uint8_t> insert;
        for (const char* h = edits[e].hex; h[0] && h[1]; h += 2)
            insert.push_back(uint8_t(std::stoi(std::string(h, 2), nullptr, 16)));
        jpeg.erase(jpeg.begin() + long(edits[e].offset),
                   jpeg.begin() + long(edits[e].offset + edits[e].erase));
        jpeg.insert(jpeg.begin() + long(edits[e].offset), insert.begin(), insert.end());
    }
    return jpeg;
}

} // namespace hemi::test
