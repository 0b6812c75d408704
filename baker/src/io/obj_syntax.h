#pragma once
// OBJ syntax shared by the in-memory reader (obj.cpp) and the streaming reader (obj_stream.cpp):
// logical lines, statement keywords, number lists and face corners, with the same messages.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "io/text_scan.h"

namespace lodbake::detail::obj {

constexpr size_t kMaxLineBytes = size_t(1) << 20;
constexpr uint32_t kNone = 0xffffffffu;

// Hands out logical lines: physical lines without their end-of-line bytes (LF or CRLF), joined when
// one ends in a backslash, with comments ('#' at the start or after white space) removed.
class LineReader {
public:
    // `lines_before`: physical lines that came before `data` (the streaming reader's earlier windows).
    LineReader(const uint8_t* data, size_t size, uint64_t lines_before = 0)
        : p_(reinterpret_cast<const char*>(data)), end_(reinterpret_cast<const char*>(data) + size),
          physical_(lines_before) {}

    // Physical lines handed out so far, counting lines_before.
    uint64_t physicalLines() const { return physical_; }

    // False at the end of the input. On success `line_number` is the 1-based number of the first
    // physical line. `error` is set (and false returned) for an over-long line.
    bool next(std::string_view& line, uint64_t& line_number, std::string& error) {
        if (p_ >= end_) return false;
        line_number = physical_ + 1;
        std::string_view phys = takePhysical();
        if (phys.size() > kMaxLineBytes) return tooLong(line_number, error);
        if (!endsWithBackslash(phys)) {
            line = stripComment(phys);
            return true;
        }
        joined_.clear();
        for (;;) {
            std::string_view body = detail::trim(phys);
            body.remove_suffix(1); // the backslash
            joined_.append(body.data(), body.size());
            joined_ += ' ';
            if (joined_.size() > kMaxLineBytes) return tooLong(line_number, error);
            if (p_ >= end_) break;
            phys = takePhysical();
            if (phys.size() > kMaxLineBytes) return tooLong(line_number, error);
            if (!endsWithBackslash(phys)) {
                joined_.append(phys.data(), phys.size());
                break;
            }
        }
        if (joined_.size() > kMaxLineBytes) return tooLong(line_number, error);
        line = stripComment(joined_);
        return true;
    }

private:
    const char* p_;
    const char* end_;
    uint64_t physical_ = 0;
    std::string joined_;

    std::string_view takePhysical() {
        const char* nl = static_cast<const char*>(std::memchr(p_, '\n', size_t(end_ - p_)));
        const char* stop = nl ? nl : end_;
        std::string_view s(p_, size_t(stop - p_));
        p_ = nl ? nl + 1 : end_;
        ++physical_;
        if (!s.empty() && s.back() == '\r') s.remove_suffix(1);
        return s;
    }
    static bool endsWithBackslash(std::string_view s) {
        s = detail::trim(s);
        return !s.empty() && s.back() == '\\';
    }
    static std::string_view stripComment(std::string_view s) {
        size_t pos = s.find('#');
        while (pos != std::string_view::npos) {
            if (pos == 0 || detail::isSpace(s[pos - 1])) return s.substr(0, pos);
            pos = s.find('#', pos + 1);
        }
        return s;
    }
    static bool tooLong(uint64_t line_number, std::string& error) {
        error = "line " + std::to_string(line_number) + ": longer than " + std::to_string(kMaxLineBytes) + " bytes";
        return false;
    }
};

inline bool isKeywordChar(char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

inline bool isPlainKeyword(std::string_view s) {
    if (s.empty() || s.size() > 32) return false;
    for (char c : s)
        if (!isKeywordChar(c)) return false;
    return true;
}

struct Corner {
    uint32_t v = 0;
    uint32_t vt = kNone;
    uint32_t vn = kNone;
};

/// Reads between min_count and max_count finite numbers from `rest`; "" on success, else what was
/// expected ("<key>: ...", without the line).
inline std::string readObjFloats(std::string_view key, std::string_view rest, float* out, size_t min_count,
                                 size_t max_count, size_t& count) {
    count = 0;
    for (;;) {
        const std::string_view tok = nextToken(rest);
        if (tok.empty()) break;
        if (count == max_count)
            return std::string(key) + ": expected at most " + std::to_string(max_count) + " numbers, got '" +
                   excerpt(tok) + "' after them";
        float v = 0.0f;
        if (!parseFloat(tok, v)) return std::string(key) + ": expected a number, got '" + excerpt(tok) + "'";
        if (!std::isfinite(v)) return std::string(key) + ": coordinate is not finite ('" + excerpt(tok) + "')";
        out[count++] = v;
    }
    if (count < min_count)
        return std::string(key) + ": expected at least " + std::to_string(min_count) + " numbers, got " +
               std::to_string(count);
    return std::string();
}

/// Resolves one OBJ index (1-based, or negative: relative to the `defined` elements so far); "" or
/// what was expected.
inline std::string resolveObjIndex(std::string_view tok, const char* what, size_t defined, uint32_t& out) {
    int64_t idx = 0;
    if (!parseInt(tok, idx))
        return "f: " + std::string(what) + " index: expected an integer, got '" + excerpt(tok) + "'";
    if (idx == 0) return "f: " + std::string(what) + " index 0 is invalid (OBJ indices start at 1)";
    const int64_t resolved = idx > 0 ? idx - 1 : int64_t(defined) + idx;
    if (resolved < 0 || resolved >= int64_t(defined))
        return "f: " + std::string(what) + " index " + std::to_string(idx) + " out of range (" +
               std::to_string(defined) + " defined so far)";
    out = uint32_t(resolved);
    return std::string();
}

/// One face corner v, v/vt, v//vn or v/vt/vn against the counts defined so far; "" or what was expected.
inline std::string parseObjCorner(std::string_view tok, size_t positions, size_t texcoords, size_t normals,
                                  Corner& c) {
    const size_t s1 = tok.find('/');
    std::string what = resolveObjIndex(tok.substr(0, s1), "vertex", positions, c.v);
    if (!what.empty()) return what;
    c.vt = c.vn = kNone;
    if (s1 == std::string_view::npos) return what;
    const std::string_view after = tok.substr(s1 + 1);
    if (after.empty()) return "f: expected v, v/vt, v//vn or v/vt/vn, got '" + excerpt(tok) + "'";
    const size_t s2 = after.find('/');
    const std::string_view vt = after.substr(0, s2);
    if (!vt.empty() && !(what = resolveObjIndex(vt, "texture coordinate", texcoords, c.vt)).empty()) return what;
    if (s2 == std::string_view::npos) return what;
    const std::string_view vn = after.substr(s2 + 1);
    if (vn.empty() && vt.empty()) return "f: expected v, v/vt, v//vn or v/vt/vn, got '" + excerpt(tok) + "'";
    if (!vn.empty()) what = resolveObjIndex(vn, "normal", normals, c.vn);
    return what;
}

} // namespace lodbake::detail::obj
