#include "lodbake/core/json_writer.h"

#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace lodbake {

std::string JsonWriter::escape(const std::string& s) {
    std::string out = "\"";
    for (unsigned char c : s) {
        switch (c) {
        case '"': out += "\\\""; break;
        case '\\': out += "\\\\"; break;
        case '\n': out += "\\n"; break;
        case '\r': out += "\\r"; break;
        case '\t': out += "\\t"; break;
        default:
            if (c < 0x20) {
                char buf[8];
                std::snprintf(buf, sizeof(buf), "\\u%04x", c);
                out += buf;
            } else {
                out += char(c);
            }
        }
    }
    return out + "\"";
}

std::string JsonWriter::formatNumber(double d) {
    if (!std::isfinite(d)) return "null";
    if (d == 0.0) return "0";
    // Shortest %.{p}g that reads back to the same double.
    char buf[40];
    for (int precision = 1; precision <= 17; ++precision) {
        std::snprintf(buf, sizeof(buf), "%.*g", precision, d);
        if (std::strtod(buf, nullptr) == d) break;
    }
    return buf;
}

void JsonWriter::newline() {
    if (indent_ <= 0) return;
    out_ += '\n';
    out_.append(has_items_.size() * size_t(indent_), ' ');
}

void JsonWriter::beforeValue() {
    if (after_key_) {
        after_key_ = false;
        return;
    }
    if (!has_items_.empty()) {
        if (has_items_.back()) out_ += ',';
        has_items_.back() = true;
        newline();
    }
}

JsonWriter& JsonWriter::key(const std::string& k) {
    assert(!has_items_.empty());
    if (has_items_.back()) out_ += ',';
    has_items_.back() = true;
    newline();
    out_ += escape(k);
    out_ += indent_ > 0 ? ": " : ":";
    after_key_ = true;
    return *this;
}

JsonWriter& JsonWriter::beginObject() {
    beforeValue();
    out_ += '{';
    has_items_.push_back(false);
    return *this;
}

JsonWriter& JsonWriter::endObject() {
    const bool had = has_items_.back();
    has_items_.pop_back();
    if (had) newline();
    out_ += '}';
    if (has_items_.empty()) out_ += '\n';
    return *this;
}

JsonWriter& JsonWriter::beginArray() {
    beforeValue();
    out_ += '[';
    has_items_.push_back(false);
    return *this;
}

JsonWriter& JsonWriter::endArray() {
    const bool had = has_items_.back();
    has_items_.pop_back();
    if (had) newline();
    out_ += ']';
    if (has_items_.empty()) out_ += '\n';
    return *this;
}

JsonWriter& JsonWriter::value(const std::string& s) {
    beforeValue();
    out_ += escape(s);
    return *this;
}

JsonWriter& JsonWriter::value(double d) {
    beforeValue();
    out_ += formatNumber(d);
    return *this;
}

JsonWriter& JsonWriter::value(int64_t i) {
    beforeValue();
    out_ += std::to_string(i);
    return *this;
}

JsonWriter& JsonWriter::value(uint64_t u) {
    beforeValue();
    out_ += std::to_string(u);
    return *this;
}

JsonWriter& JsonWriter::value(bool b) {
    beforeValue();
    out_ += b ? "true" : "false";
    return *this;
}

JsonWriter& JsonWriter::null() {
    beforeValue();
    out_ += "null";
    return *this;
}

} // namespace lodbake
