#pragma once
// Internal helpers shared by the text mesh readers and writers (OBJ, OFF): locale-independent number
// parsing and formatting with <charconv>, printable excerpts of hostile bytes for one-line error
// messages, and the sRGB transfer function for colours.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

namespace lodbake::detail {

inline bool isSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

/// Splits the next whitespace-separated token off the front of `s` (empty when none is left).
inline std::string_view nextToken(std::string_view& s) {
    size_t i = 0;
    while (i < s.size() && isSpace(s[i])) ++i;
    size_t j = i;
    while (j < s.size() && !isSpace(s[j])) ++j;
    std::string_view tok = s.substr(i, j - i);
    s.remove_prefix(j);
    return tok;
}

inline std::string_view trim(std::string_view s) {
    while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
    while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
    return s;
}

/// Parses the whole token as a float (a leading '+' is accepted). False for anything else,
/// including values outside the float range. NaN and infinity parse; callers check isfinite.
inline bool parseFloat(std::string_view tok, float& out) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    if (tok.empty()) return false;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return r.ec == std::errc() && r.ptr == tok.data() + tok.size();
}

/// Parses the whole token as a signed decimal integer (a leading '+' is accepted).
inline bool parseInt(std::string_view tok, int64_t& out) {
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    if (tok.empty()) return false;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), out);
    return r.ec == std::errc() && r.ptr == tok.data() + tok.size();
}

/// A short, printable, single-line rendering of untrusted bytes for error messages: at most 32
/// characters, non-printable bytes as \xNN.
inline std::string excerpt(std::string_view s) {
    static const char* kHex = "0123456789abcdef";
    std::string out;
    const size_t n = s.size() < 32 ? s.size() : 32;
    for (size_t i = 0; i < n; ++i) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            out += "\\x";
            out += kHex[c >> 4];
            out += kHex[c & 15];
        }
    }
    if (s.size() > n) out += "...";
    return out;
}

/// Replaces every byte that is not part of a well-formed UTF-8 sequence with '?', so names taken
/// from files can go into JSON (glTF) safely. Returns true if anything was replaced.
inline bool sanitizeUtf8(std::string& s) {
    bool changed = false;
    size_t i = 0;
    while (i < s.size()) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        size_t len = c < 0x80                   ? 1
                     : (c >= 0xc2 && c <= 0xdf) ? 2
                     : (c >= 0xe0 && c <= 0xef) ? 3
                     : (c >= 0xf0 && c <= 0xf4) ? 4
                                                : 0;
        bool ok = len > 0 && i + len <= s.size();
        for (size_t k = 1; ok && k < len; ++k) ok = (static_cast<unsigned char>(s[i + k]) & 0xc0) == 0x80;
        if (ok && len >= 3) {
            // Reject overlong forms, surrogates and code points above U+10FFFF.
            const unsigned char c1 = static_cast<unsigned char>(s[i + 1]);
            if (c == 0xe0 && c1 < 0xa0) ok = false;
            if (c == 0xed && c1 >= 0xa0) ok = false;
            if (c == 0xf0 && c1 < 0x90) ok = false;
            if (c == 0xf4 && c1 >= 0x90) ok = false;
        }
        if (ok && (c >= 0x20 || c == '\t')) {
            i += len;
        } else {
            s[i] = '?';
            changed = true;
            ++i;
        }
    }
    return changed;
}

/// Shortest text that reads back to exactly `v` (std::to_chars), so writers are deterministic.
inline void appendFloat(std::string& out, float v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out.append(buf, r.ptr);
}

inline void appendUint(std::string& out, uint64_t v) {
    char buf[24];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);
    out.append(buf, r.ptr);
}

/// IEC 61966-2-1 sRGB decoding and encoding of one channel, input clamped to [0,1].
inline float srgbToLinear(float c) {
    c = c < 0.0f ? 0.0f : (c > 1.0f ? 1.0f : c);
    return c <= 0.04045f ? c / 12.92f : float(std::pow((double(c) + 0.055) / 1.055, 2.4));
}
inline float linearToSrgb(float c) {
    c = c < 0.0f ? 0.0f : (c > 1.0f ? 1.0f : c);
    return c <= 0.0031308f ? c * 12.92f : float(1.055 * std::pow(double(c), 1.0 / 2.4) - 0.055);
}

} // namespace lodbake::detail
