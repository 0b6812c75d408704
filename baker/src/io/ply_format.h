#pragma once
// The PLY header, the body cursor and the checks shared by the in-memory reader (ply.cpp) and the
// streaming reader (ply_stream.cpp): both parse the same header the same way and read scalars of
// every encoding through the same cursor, so a file means the same to both.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/status.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake::ply_detail {

enum class ScalarType : uint8_t { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

inline bool parseScalarType(const std::string& s, ScalarType& out) {
    static const std::pair<const char*, ScalarType> kNames[] = {
        {"char", ScalarType::Int8},     {"int8", ScalarType::Int8},       {"uchar", ScalarType::Uint8},
        {"uint8", ScalarType::Uint8},   {"short", ScalarType::Int16},     {"int16", ScalarType::Int16},
        {"ushort", ScalarType::Uint16}, {"uint16", ScalarType::Uint16},   {"int", ScalarType::Int32},
        {"int32", ScalarType::Int32},   {"uint", ScalarType::Uint32},     {"uint32", ScalarType::Uint32},
        {"float", ScalarType::Float32}, {"float32", ScalarType::Float32}, {"double", ScalarType::Float64},
        {"float64", ScalarType::Float64},
    };
    for (const auto& n : kNames)
        if (s == n.first) {
            out = n.second;
            return true;
        }
    return false;
}

inline size_t scalarSize(ScalarType t) {
    switch (t) {
    case ScalarType::Int8:
    case ScalarType::Uint8: return 1;
    case ScalarType::Int16:
    case ScalarType::Uint16: return 2;
    case ScalarType::Int32:
    case ScalarType::Uint32:
    case ScalarType::Float32: return 4;
    case ScalarType::Float64: return 8;
    }
    return 1;
}

inline bool isIntegerType(ScalarType t) { return t != ScalarType::Float32 && t != ScalarType::Float64; }

// Largest value of an integer type, used to normalise integer colour channels.
inline double integerTypeMax(ScalarType t) {
    switch (t) {
    case ScalarType::Int8: return 127.0;
    case ScalarType::Uint8: return 255.0;
    case ScalarType::Int16: return 32767.0;
    case ScalarType::Uint16: return 65535.0;
    case ScalarType::Int32: return 2147483647.0;
    case ScalarType::Uint32: return 4294967295.0;
    default: return 1.0;
    }
}

enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct Property {
    std::string name;
    bool is_list = false;
    ScalarType count_type = ScalarType::Uint8; // lists only
    ScalarType value_type = ScalarType::Float32;
};

struct Element {
    std::string name;
    uint64_t count = 0;
    std::vector<Property> properties;

    int findProperty(const std::string& n) const {
        for (size_t i = 0; i < properties.size(); ++i)
            if (properties[i].name == n) return int(i);
        return -1;
    }
};

struct Header {
    Encoding encoding = Encoding::Ascii;
    std::vector<Element> elements;
    int64_t num_cols = -1; // obj_info num_cols (range grids)
    int64_t num_rows = -1;
    size_t body_offset = 0;
};

inline const char* encodingName(Encoding e) {
    switch (e) {
    case Encoding::Ascii: return "ascii";
    case Encoding::BinaryLittleEndian: return "binary_little_endian";
    case Encoding::BinaryBigEndian: return "binary_big_endian";
    }
    return "ascii";
}

// Makes arbitrary file bytes safe to quote inside a one-line message.
inline std::string quoted(const char* p, size_t n) {
    static const char kHex[] = "0123456789abcdef";
    std::string out = "'";
    const size_t shown = std::min<size_t>(n, 40);
    for (size_t i = 0; i < shown; ++i) {
        const unsigned char c = static_cast<unsigned char>(p[i]);
        if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
            out += char(c);
        } else {
            out += "\\x";
            out += kHex[c >> 4];
            out += kHex[c & 15];
        }
    }
    if (shown < n) out += "...";
    out += "'";
    return out;
}
inline std::string quoted(const std::string& s) { return quoted(s.data(), s.size()); }

inline bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

inline std::vector<std::string> splitWords(const char* p, const char* end) {
    std::vector<std::string> words;
    while (p < end) {
        while (p < end && isSpace(*p)) ++p;
        const char* s = p;
        while (p < end && !isSpace(*p)) ++p;
        if (p > s) words.emplace_back(s, p);
    }
    return words;
}

// Element and property names end up in messages, so they must be printable ASCII.
inline bool isPrintableName(const std::string& s) {
    for (char c : s)
        if (static_cast<unsigned char>(c) < 0x21 || static_cast<unsigned char>(c) > 0x7e) return false;
    return !s.empty();
}

inline bool parseUnsigned(const std::string& s, uint64_t& out) {
    const char* b = s.data();
    const char* e = b + s.size();
    if (b < e && *b == '+') ++b;
    auto r = std::from_chars(b, e, out);
    return r.ec == std::errc() && r.ptr == e && b < e;
}

inline Result<Header> parseHeader(const uint8_t* data, size_t size, const std::string& name, Diagnostics& diagnostics) {
    const char* text = reinterpret_cast<const char*>(data);
    const char* end = text + size;
    if (size < 3 || std::memcmp(text, "ply", 3) != 0 ||
        (size > 3 && text[3] != '\n' && text[3] != '\r' && text[3] != ' ')) {
        return invalidInput(name + ": header: expected the magic word 'ply' on the first line, got " +
                            quoted(text, std::min<size_t>(size, 8)));
    }
    // Find end_header first: a file without it would otherwise fail on whatever body line comes next.
    static const char kEndHeader[] = "end_header";
    const char* found = std::search(text, end, kEndHeader, kEndHeader + sizeof(kEndHeader) - 1);
    if (found == end) return invalidInput(name + ": header: no 'end_header' line");

    Header header;
    bool has_format = false;
    size_t line_number = 0;
    size_t bye_lines = 0;
    const char* p = text;
    while (true) {
        if (p >= end) return invalidInput(name + ": header: no 'end_header' line");
        const char* nl = static_cast<const char*>(std::memchr(p, '\n', size_t(end - p)));
        const char* line_end = nl ? nl : end;
        const char* next = nl ? nl + 1 : end;
        ++line_number;
        const std::string where = name + ": header line " + std::to_string(line_number);
        const std::vector<std::string> words = splitWords(p, line_end);
        p = next;
        if (line_number == 1) continue; // the magic, checked above
        if (words.empty()) continue;
        const std::string& keyword = words[0];
        if (keyword == "comment") continue;
        if (keyword == "obj_info") {
            if (words.size() >= 3 && (words[1] == "num_cols" || words[1] == "num_rows")) {
                uint64_t v = 0;
                if (!parseUnsigned(words[2], v) || v > (uint64_t(1) << 31))
                    return invalidInput(where + ": obj_info " + words[1] + ": expected a non-negative integer, got " +
                                        quoted(words[2]));
                (words[1] == "num_cols" ? header.num_cols : header.num_rows) = int64_t(v);
            }
            continue;
        }
        if (keyword == "bye") {
            // Some Stanford range scans carry these; strict readers reject them. Harmless.
            ++bye_lines;
            continue;
        }
        if (keyword == "end_header") {
            if (words.size() != 1) return invalidInput(where + ": end_header: unexpected text after it");
            if (!nl) return invalidInput(where + ": end_header: expected a line break after it");
            header.body_offset = size_t(next - text);
            break;
        }
        if (keyword == "format") {
            if (has_format) return invalidInput(where + ": format: given twice");
            if (words.size() != 3) return invalidInput(where + ": format: expected 'format <encoding> 1.0'");
            if (words[1] == "ascii") header.encoding = Encoding::Ascii;
            else if (words[1] == "binary_little_endian") header.encoding = Encoding::BinaryLittleEndian;
            else if (words[1] == "binary_big_endian") header.encoding = Encoding::BinaryBigEndian;
            else
                return invalidInput(where + ": format: expected ascii, binary_little_endian or binary_big_endian, got " +
                                    quoted(words[1]));
            if (words[2] != "1.0" && words[2] != "1")
                return unsupported(where + ": format: version " + quoted(words[2]) + " is not supported (expected 1.0)");
            has_format = true;
            continue;
        }
        if (!has_format) return invalidInput(where + ": expected 'format' before " + quoted(keyword));
        if (keyword == "element") {
            if (words.size() != 3) return invalidInput(where + ": element: expected 'element <name> <count>'");
            Element element;
            if (!isPrintableName(words[1]))
                return invalidInput(where + ": element: name " + quoted(words[1]) + " is not printable ASCII");
            element.name = words[1];
            if (!words[2].empty() && words[2][0] == '-')
                return invalidInput(where + ": element " + words[1] + ": negative count " + quoted(words[2]));
            if (!parseUnsigned(words[2], element.count))
                return invalidInput(where + ": element " + words[1] + ": expected a count, got " + quoted(words[2]));
            header.elements.push_back(std::move(element));
            continue;
        }
        if (keyword == "property") {
            if (header.elements.empty()) return invalidInput(where + ": property before any element");
            Element& element = header.elements.back();
            Property prop;
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5)
                    return invalidInput(where + ": element " + element.name +
                                        ": expected 'property list <count type> <value type> <name>'");
                if (!parseScalarType(words[2], prop.count_type))
                    return invalidInput(where + ": element " + element.name + ": unknown property type " + quoted(words[2]));
                if (!parseScalarType(words[3], prop.value_type))
                    return invalidInput(where + ": element " + element.name + ": unknown property type " + quoted(words[3]));
                if (!isIntegerType(prop.count_type))
                    return invalidInput(where + ": element " + element.name + ": list count type must be an integer type, got " +
                                        quoted(words[2]));
                prop.is_list = true;
                prop.name = words[4];
            } else {
                if (words.size() != 3)
                    return invalidInput(where + ": element " + element.name + ": expected 'property <type> <name>'");
                if (!parseScalarType(words[1], prop.value_type))
                    return invalidInput(where + ": element " + element.name + ": unknown property type " + quoted(words[1]));
                prop.name = words[2];
            }
            if (!isPrintableName(prop.name))
                return invalidInput(where + ": element " + element.name + ": property name " + quoted(prop.name) +
                                    " is not printable ASCII");
            if (element.findProperty(prop.name) >= 0)
                return invalidInput(where + ": element " + element.name + ": property " + quoted(prop.name) +
                                    " declared twice");
            element.properties.push_back(std::move(prop));
            continue;
        }
        return invalidInput(where + ": unknown keyword " + quoted(keyword));
    }
    if (!has_format) return invalidInput(name + ": header: no 'format' line");
    if (bye_lines > 0)
        diagnostics.note(name + ": header: ignored " + std::to_string(bye_lines) + " non-standard 'bye' line(s)");
    return header;
}

enum class ReadError { None, End, NotNumber, NotInteger, OutOfRange };

// A cursor over the body that reads one scalar at a time, whatever the encoding.
class BodyCursor {
public:
    BodyCursor(const uint8_t* data, size_t size, size_t pos, Encoding encoding)
        : data_(data), size_(size), pos_(pos), encoding_(encoding) {}

    /// Moves the cursor to another buffer (the streaming reader's next window of the file).
    void reset(const uint8_t* data, size_t size, size_t pos) {
        data_ = data;
        size_ = size;
        pos_ = pos;
    }

    size_t remaining() const { return size_ - pos_; }
    size_t position() const { return pos_; }
    const std::string& lastToken() const { return token_; }

    ReadError read(ScalarType t, double& out) {
        if (encoding_ == Encoding::Ascii) return readAscii(t, out);
        return readBinary(t, out);
    }

    // Skips `count` values of type `t` without converting them.
    ReadError skip(ScalarType t, uint64_t count) {
        if (encoding_ != Encoding::Ascii) {
            const uint64_t bytes = count * scalarSize(t);
            if (count > remaining() || bytes > remaining()) return ReadError::End;
            pos_ += size_t(bytes);
            return ReadError::None;
        }
        // Skipped ascii values only need to be numbers: writers are often loose with the declared
        // type of properties nobody reads (a "uchar" intensity written as 0.5).
        (void)t;
        double ignored = 0;
        for (uint64_t i = 0; i < count; ++i) {
            const ReadError e = readAscii(ScalarType::Float64, ignored);
            if (e != ReadError::None) return e;
        }
        return ReadError::None;
    }

    // After the last element: anything but whitespace (ascii) or any byte (binary) is left over.
    size_t trailingBytes() const {
        if (encoding_ != Encoding::Ascii) return remaining();
        size_t p = pos_;
        while (p < size_ && isSpace(char(data_[p]))) ++p;
        return size_ - p;
    }

private:
    ReadError readBinary(ScalarType t, double& out) {
        const size_t n = scalarSize(t);
        if (remaining() < n) return ReadError::End;
        uint8_t b[8];
        std::memcpy(b, data_ + pos_, n);
        pos_ += n;
        if (encoding_ == Encoding::BinaryBigEndian) std::reverse(b, b + n);
        switch (t) {
        case ScalarType::Int8: out = double(int8_t(b[0])); break;
        case ScalarType::Uint8: out = double(b[0]); break;
        case ScalarType::Int16: { int16_t v; std::memcpy(&v, b, 2); out = v; break; }
        case ScalarType::Uint16: { uint16_t v; std::memcpy(&v, b, 2); out = v; break; }
        case ScalarType::Int32: { int32_t v; std::memcpy(&v, b, 4); out = v; break; }
        case ScalarType::Uint32: { uint32_t v; std::memcpy(&v, b, 4); out = v; break; }
        case ScalarType::Float32: { float v; std::memcpy(&v, b, 4); out = v; break; }
        case ScalarType::Float64: { double v; std::memcpy(&v, b, 8); out = v; break; }
        }
        return ReadError::None;
    }

    ReadError readAscii(ScalarType t, double& out) {
        const char* p = reinterpret_cast<const char*>(data_) + pos_;
        const char* end = reinterpret_cast<const char*>(data_) + size_;
        while (p < end && isSpace(*p)) ++p;
        if (p == end) {
            pos_ = size_;
            return ReadError::End;
        }
        const char* s = p;
        while (p < end && !isSpace(*p)) ++p;
        pos_ = size_t(p - reinterpret_cast<const char*>(data_));
        const char* b = s;
        if (*b == '+' && p - b > 1) ++b;
        if (isIntegerType(t)) {
            int64_t v = 0;
            const auto r = std::from_chars(b, p, v);
            if (r.ec == std::errc::result_out_of_range) return fail(s, p, ReadError::OutOfRange);
            if (r.ec != std::errc() || r.ptr != p) {
                double d = 0;
                const auto rd = std::from_chars(b, p, d);
                return fail(s, p, rd.ec == std::errc() && rd.ptr == p ? ReadError::NotInteger : ReadError::NotNumber);
            }
            const double lo = t == ScalarType::Int8 ? -128.0 : t == ScalarType::Int16 ? -32768.0
                            : t == ScalarType::Int32 ? -2147483648.0 : 0.0;
            if (double(v) < lo || double(v) > integerTypeMax(t)) return fail(s, p, ReadError::OutOfRange);
            out = double(v);
            return ReadError::None;
        }
        double v = 0;
        const auto r = std::from_chars(b, p, v, std::chars_format::general);
        if (r.ec == std::errc::result_out_of_range) {
            out = (*b == '-') ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
            return ReadError::None; // an overflow is reported like any other non-finite value
        }
        if (r.ec != std::errc() || r.ptr != p) return fail(s, p, ReadError::NotNumber);
        out = t == ScalarType::Float32 ? double(float(v)) : v;
        return ReadError::None;
    }

    ReadError fail(const char* s, const char* p, ReadError e) {
        token_.assign(s, p);
        return e;
    }

    const uint8_t* data_;
    size_t size_;
    size_t pos_;
    Encoding encoding_;
    std::string token_;
};

// Smallest number of body bytes one record of `element` can take (lists empty).
inline uint64_t minRecordBytes(const Element& element, Encoding encoding) {
    uint64_t n = 0;
    for (const Property& p : element.properties) {
        if (encoding == Encoding::Ascii) n += 2; // one character and one separator per value
        else n += scalarSize(p.is_list ? p.count_type : p.value_type);
    }
    return n;
}


inline std::string describeError(ReadError e, const BodyCursor& cursor, ScalarType t) {
    switch (e) {
    case ReadError::End: return "file ends early (expected more data)";
    case ReadError::NotNumber: return "expected a number, got " + quoted(cursor.lastToken());
    case ReadError::NotInteger: return "expected an integer, got " + quoted(cursor.lastToken());
    case ReadError::OutOfRange:
        return "value " + quoted(cursor.lastToken()) + " does not fit the property type (" +
               (isIntegerType(t) ? "integer" : "real") + ")";
    case ReadError::None: break;
    }
    return "unknown read error";
}


// Index of the first 'vertex' element, after checking it has scalar x, y, z and a count within limits.
inline Result<size_t> findVertexElement(const Header& header, const std::string& name, const ReadOptions& options) {
    int vertex_element = -1;
    for (size_t i = 0; i < header.elements.size(); ++i)
        if (header.elements[i].name == "vertex" && vertex_element < 0) vertex_element = int(i);
    if (vertex_element < 0) return invalidInput(name + ": header: no 'element vertex'");
    const Element& vel = header.elements[size_t(vertex_element)];
    for (const char* axis : {"x", "y", "z"}) {
        const int pi = vel.findProperty(axis);
        if (pi < 0) return invalidInput(name + ": header: element vertex has no property '" + axis + "'");
        if (vel.properties[size_t(pi)].is_list)
            return invalidInput(name + ": header: element vertex property '" + std::string(axis) + "' is a list");
    }
    const uint64_t vertex_count = vel.count;
    if (vertex_count == 0) return invalidInput(name + ": vertex: no vertices");
    if (vertex_count > options.max_vertex_count)
        return resourceLimit(name + ": header: element vertex count " + std::to_string(vertex_count) +
                             " exceeds the limit of " + std::to_string(options.max_vertex_count));
    return size_t(vertex_element);
}

// Refuses counts the remaining bytes cannot hold, before anything is allocated.
inline Status checkBodyHoldsCounts(const Header& header, size_t size, const std::string& name) {
    const uint64_t body = size - header.body_offset;
    uint64_t needed = 0;
    for (const Element& el : header.elements) {
        const uint64_t per = minRecordBytes(el, header.encoding);
        const uint64_t ascii_slack = header.encoding == Encoding::Ascii ? 1 : 0; // last value needs no separator
        if (per > 0 && el.count > (body + ascii_slack) / per)
            return invalidInput(name + ": header: element " + el.name + " count " + std::to_string(el.count) +
                                " needs at least " + std::to_string(el.count) + " x " + std::to_string(per) +
                                " bytes but the body has " + std::to_string(body));
        needed += el.count * per;
        if (needed > body + ascii_slack)
            return invalidInput(name + ": header: elements up to " + el.name + " need at least " +
                                std::to_string(needed) + " bytes but the body has " + std::to_string(body));
    }
    return Status::okStatus();
}


} // namespace lodbake::ply_detail
