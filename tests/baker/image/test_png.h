#pragma once
// PNG files made in the tests, byte by byte (stored deflate blocks: no compressor needed), so image
// cases need no image library: 8- or 16-bit samples, 1 to 4 channels.

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace lodbake_test {

inline uint32_t pngCrc32(const uint8_t* data, size_t size) {
    uint32_t crc = 0xffffffffu;
    for (size_t i = 0; i < size; ++i) {
        crc ^= data[i];
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

inline void pngPutU32(std::vector<uint8_t>& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(uint8_t(v >> shift));
}

inline void pngChunk(std::vector<uint8_t>& out, const char* type, const std::vector<uint8_t>& body) {
    pngPutU32(out, uint32_t(body.size()));
    std::vector<uint8_t> typed(type, type + 4);
    typed.insert(typed.end(), body.begin(), body.end());
    out.insert(out.end(), typed.begin(), typed.end());
    pngPutU32(out, pngCrc32(typed.data(), typed.size()));
}

/// A PNG of width x height pixels; `samples` holds channels values per pixel, rows top to bottom,
/// each below 2^bits (bits 8 or 16).
inline std::vector<uint8_t> makePng(uint32_t width, uint32_t height, uint32_t channels, uint32_t bits,
                                    const std::vector<uint32_t>& samples) {
    static const uint8_t kColourType[5] = {0, 0, 4, 2, 6}; // by channel count: grey, grey+alpha, RGB, RGBA
    std::vector<uint8_t> raw;
    for (uint32_t y = 0; y < height; ++y) {
        raw.push_back(0); // filter: none
        for (uint32_t i = 0; i < width * channels; ++i) {
            const uint32_t v = samples[size_t(y) * width * channels + i];
            if (bits == 16) raw.push_back(uint8_t(v >> 8));
            raw.push_back(uint8_t(v));
        }
    }
    std::vector<uint8_t> z{0x78, 0x01};
    for (size_t at = 0; at < raw.size() || at == 0;) {
        const size_t n = std::min<size_t>(65535, raw.size() - at);
        z.push_back(at + n == raw.size() ? 1 : 0);
        z.push_back(uint8_t(n));
        z.push_back(uint8_t(n >> 8));
        z.push_back(uint8_t(~n));
        z.push_back(uint8_t(~n >> 8));
        z.insert(z.end(), raw.begin() + long(at), raw.begin() + long(at + n));
        at += n;
        if (n == 0) break;
    }
    uint32_t a = 1, b = 0;
    for (uint8_t c : raw) {
        a = (a + c) % 65521;
        b = (b + a) % 65521;
    }
    pngPutU32(z, (b << 16) | a);
    std::vector<uint8_t> png{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    pngPutU32(ihdr, width);
    pngPutU32(ihdr, height);
    ihdr.insert(ihdr.end(), {uint8_t(bits), kColourType[channels], 0, 0, 0});
    pngChunk(png, "IHDR", ihdr);
    pngChunk(png, "IDAT", z);
    pngChunk(png, "IEND", {});
    return png;
}

/// An RGB8 PNG whose pixel (x, y) is colour(x, y) = {r, g, b}.
template <class ColourFn> std::vector<uint8_t> makeRgbPng(uint32_t width, uint32_t height, ColourFn colour) {
    std::vector<uint32_t> samples;
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x) {
            const std::array<uint32_t, 3> c = colour(x, y);
            samples.insert(samples.end(), c.begin(), c.end());
        }
    return makePng(width, height, 3, 8, samples);
}

} // namespace lodbake_test
