// Strict, non-recursive JSON parser (RFC 8259) with UTF-8 validation per RFC 3629 / Unicode Table 3-7.
#include "lodrt/json.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <system_error>

#include "memory.h"

namespace lodrt {
namespace detail {

struct JsonNode {
    double number;
    uint32_t first;      // String: offset into strings_; Array/Object: offset into children_
    uint32_t count;      // String: byte length; Array/Object: number of children
    uint32_t key_offset; // member of an object: key offset into strings_
    uint32_t key_length;
    JsonType type;
};

} // namespace detail

using detail::Growable;
using detail::JsonNode;

namespace {

constexpr uint32_t kDefaultMaxDepth = 64;
constexpr uint32_t kDefaultMaxNodes = 1u << 22;
constexpr uint32_t kDefaultMaxStringLength = 1u << 26;

bool isSpace(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}
bool isDigit(char c) {
    return c >= '0' && c <= '9';
}

int hexValue(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

struct Frame {
    uint32_t node;
    uint32_t scratch_begin;
};

} // namespace

// Holds the growing arrays while parsing; the finished arrays move into the JsonDocument.
struct JsonParser {
    const char* text;
    size_t size;
    size_t pos = 0;
    Allocator allocator;
    uint32_t max_depth;
    uint32_t max_nodes;
    uint32_t max_string_length;

    Growable<JsonNode> nodes;
    Growable<uint32_t> children;
    Growable<char> strings;
    Growable<uint32_t> scratch; // children of the open containers, innermost last
    Growable<Frame> stack;

    static void clear(JsonDocument* out) { out->release(); }

    void moveInto(JsonDocument* out) {
        out->allocator_ = allocator;
        out->node_count_ = uint32_t(nodes.size);
        out->nodes_ = nodes.release();
        out->children_count_ = uint32_t(children.size);
        out->children_ = children.release();
        out->strings_size_ = strings.size;
        out->strings_ = strings.release();
    }

    ~JsonParser() {
        nodes.reset(allocator);
        children.reset(allocator);
        strings.reset(allocator);
        scratch.reset(allocator);
        stack.reset(allocator);
    }

    void skipSpace() {
        while (pos < size && isSpace(text[pos])) ++pos;
    }

    Result newNode(JsonType type, uint32_t key_offset, uint32_t key_length, uint32_t* index) {
        if (nodes.size >= max_nodes) return Result::JsonTooLarge;
        JsonNode node{};
        node.type = type;
        node.key_offset = key_offset;
        node.key_length = key_length;
        *index = uint32_t(nodes.size);
        if (!nodes.push(allocator, node)) return Result::OutOfMemory;
        if (!stack.size) return Result::Ok; // the root has no parent
        return scratch.push(allocator, *index) ? Result::Ok : Result::OutOfMemory;
    }

    Result appendUtf8(uint32_t code_point) {
        char bytes[4];
        size_t n = 0;
        if (code_point < 0x80) {
            bytes[n++] = char(code_point);
        } else if (code_point < 0x800) {
            bytes[n++] = char(0xC0 | (code_point >> 6));
            bytes[n++] = char(0x80 | (code_point & 0x3F));
        } else if (code_point < 0x10000) {
            bytes[n++] = char(0xE0 | (code_point >> 12));
            bytes[n++] = char(0x80 | ((code_point >> 6) & 0x3F));
            bytes[n++] = char(0x80 | (code_point & 0x3F));
        } else {
            bytes[n++] = char(0xF0 | (code_point >> 18));
            bytes[n++] = char(0x80 | ((code_point >> 12) & 0x3F));
            bytes[n++] = char(0x80 | ((code_point >> 6) & 0x3F));
            bytes[n++] = char(0x80 | (code_point & 0x3F));
        }
        return strings.append(allocator, bytes, n) ? Result::Ok : Result::OutOfMemory;
    }

    Result readHex4(uint32_t* out) {
        if (size - pos < 4) return Result::BadJson;
        uint32_t value = 0;
        for (int i = 0; i < 4; ++i) {
            int digit = hexValue(text[pos + i]);
            if (digit < 0) {
                pos += i;
                return Result::BadJson;
            }
            value = value * 16 + uint32_t(digit);
        }
        pos += 4;
        *out = value;
        return Result::Ok;
    }

    // Length of the valid UTF-8 sequence starting at text[pos] (a byte >= 0x80), or 0 if invalid.
    size_t utf8SequenceLength() const {
        const auto* p = reinterpret_cast<const uint8_t*>(text + pos);
        const size_t left = size - pos;
        const uint8_t c = p[0];
        size_t length;
        uint8_t low = 0x80, high = 0xBF; // allowed range of the second byte
        if (c >= 0xC2 && c <= 0xDF) {
            length = 2;
        } else if (c >= 0xE0 && c <= 0xEF) {
            length = 3;
            if (c == 0xE0) low = 0xA0;  // overlong
            if (c == 0xED) high = 0x9F; // UTF-16 surrogates
        } else if (c >= 0xF0 && c <= 0xF4) {
            length = 4;
            if (c == 0xF0) low = 0x90;  // overlong
            if (c == 0xF4) high = 0x8F; // above U+10FFFF
        } else {
            return 0;
        }
        if (left < length) return 0;
        if (p[1] < low || p[1] > high) return 0;
        for (size_t i = 2; i < length; ++i) {
            if (p[i] < 0x80 || p[i] > 0xBF) return 0;
        }
        return length;
    }

    // Parses the string at text[pos] == '"' and appends it, NUL-terminated, to strings.
    Result parseString(uint32_t* offset, uint32_t* length) {
        ++pos; // opening quote
        const size_t start = strings.size;
        if (start > 0xFFFFFFF0u) return Result::JsonTooLarge;
        for (;;) {
            if (strings.size - start > max_string_length) return Result::JsonTooLarge;
            if (pos >= size) return Result::BadJson;
            // Copy the run of plain ASCII in one go.
            size_t run = pos;
            while (run < size && text[run] != '"' && text[run] != '\\' && uint8_t(text[run]) >= 0x20 &&
                   uint8_t(text[run]) < 0x80)
                ++run;
            if (run > pos) {
                if (!strings.append(allocator, text + pos, run - pos)) return Result::OutOfMemory;
                pos = run;
                continue;
            }
            const uint8_t c = uint8_t(text[pos]);
            if (c == '"') {
                ++pos;
                break;
            }
            if (c < 0x20) return Result::BadJson;
            if (c >= 0x80) {
                size_t n = utf8SequenceLength();
                if (n == 0) return Result::BadUtf8;
                if (!strings.append(allocator, text + pos, n)) return Result::OutOfMemory;
                pos += n;
                continue;
            }
            // Escape.
            if (size - pos < 2) return Result::BadJson;
            const char e = text[pos + 1];
            char simple = 0;
            switch (e) {
            case '"':
                simple = '"';
                break;
            case '\\':
                simple = '\\';
                break;
            case '/':
                simple = '/';
                break;
            case 'b':
                simple = '\b';
                break;
            case 'f':
                simple = '\f';
                break;
            case 'n':
                simple = '\n';
                break;
            case 'r':
                simple = '\r';
                break;
            case 't':
                simple = '\t';
                break;
            case 'u':
                break;
            default:
                ++pos;
                return Result::BadJson;
            }
            if (simple) {
                if (!strings.push(allocator, simple)) return Result::OutOfMemory;
                pos += 2;
                continue;
            }
            pos += 2;
            uint32_t unit = 0;
            Result r = readHex4(&unit);
            if (r != Result::Ok) return r;
            uint32_t code_point = unit;
            if (unit >= 0xDC00 && unit <= 0xDFFF) return Result::BadUtf8; // lone low surrogate
            if (unit >= 0xD800 && unit <= 0xDBFF) {
                if (size - pos < 2 || text[pos] != '\\' || text[pos + 1] != 'u') return Result::BadUtf8;
                pos += 2;
                uint32_t low_unit = 0;
                r = readHex4(&low_unit);
                if (r != Result::Ok) return r;
                if (low_unit < 0xDC00 || low_unit > 0xDFFF) return Result::BadUtf8;
                code_point = 0x10000 + ((unit - 0xD800) << 10) + (low_unit - 0xDC00);
            }
            r = appendUtf8(code_point);
            if (r != Result::Ok) return r;
        }
        const size_t string_length = strings.size - start;
        if (string_length > max_string_length) return Result::JsonTooLarge;
        if (strings.size >= 0xFFFFFFF0u) return Result::JsonTooLarge;
        if (!strings.push(allocator, '\0')) return Result::OutOfMemory;
        *offset = uint32_t(start);
        *length = uint32_t(string_length);
        return Result::Ok;
    }

    Result parseNumber(double* out) {
        const size_t start = pos;
        if (pos < size && text[pos] == '-') ++pos;
        if (pos >= size || !isDigit(text[pos])) return Result::BadJson;
        if (text[pos] == '0') {
            ++pos;
        } else {
            while (pos < size && isDigit(text[pos])) ++pos;
        }
        if (pos < size && text[pos] == '.') {
            ++pos;
            if (pos >= size || !isDigit(text[pos])) return Result::BadJson;
            while (pos < size && isDigit(text[pos])) ++pos;
        }
        if (pos < size && (text[pos] == 'e' || text[pos] == 'E')) {
            ++pos;
            if (pos < size && (text[pos] == '+' || text[pos] == '-')) ++pos;
            if (pos >= size || !isDigit(text[pos])) return Result::BadJson;
            while (pos < size && isDigit(text[pos])) ++pos;
        }
        double value = 0;
        // from_chars is locale-independent, unlike strtod.
        std::from_chars_result parsed = std::from_chars(text + start, text + pos, value, std::chars_format::general);
        if (parsed.ec == std::errc::result_out_of_range) {
            pos = start;
            return Result::NumberOutOfRange;
        }
        if (parsed.ec != std::errc() || parsed.ptr != text + pos) {
            pos = start;
            return Result::BadJson;
        }
        *out = value;
        return Result::Ok;
    }

    bool matchLiteral(const char* literal) {
        const size_t n = std::strlen(literal);
        if (size - pos < n || std::memcmp(text + pos, literal, n) != 0) return false;
        pos += n;
        return true;
    }

    // Parses one value at pos. Scalars complete at once; containers push a frame.
    Result parseValue(uint32_t key_offset, uint32_t key_length) {
        skipSpace();
        if (pos >= size) return Result::BadJson;
        uint32_t index = 0;
        const char c = text[pos];
        Result r = Result::Ok;
        if (c == '{' || c == '[') {
            if (stack.size >= max_depth) return Result::JsonTooDeep;
            r = newNode(c == '{' ? JsonType::Object : JsonType::Array, key_offset, key_length, &index);
            if (r != Result::Ok) return r;
            if (!stack.push(allocator, Frame{index, uint32_t(scratch.size)})) return Result::OutOfMemory;
            ++pos;
            return Result::Ok;
        }
        if (c == '"') {
            uint32_t offset = 0, length = 0;
            r = parseString(&offset, &length);
            if (r != Result::Ok) return r;
            r = newNode(JsonType::String, key_offset, key_length, &index);
            if (r != Result::Ok) return r;
            nodes.data[index].first = offset;
            nodes.data[index].count = length;
            return Result::Ok;
        }
        if (c == '-' || isDigit(c)) {
            double value = 0;
            r = parseNumber(&value);
            if (r != Result::Ok) return r;
            r = newNode(JsonType::Number, key_offset, key_length, &index);
            if (r != Result::Ok) return r;
            nodes.data[index].number = value;
            return Result::Ok;
        }
        JsonType type;
        if (matchLiteral("true")) {
            type = JsonType::True;
        } else if (matchLiteral("false")) {
            type = JsonType::False;
        } else if (matchLiteral("null")) {
            type = JsonType::Null;
        } else {
            return Result::BadJson;
        }
        return newNode(type, key_offset, key_length, &index);
    }

    bool keyLess(uint32_t a, uint32_t b) const {
        const JsonNode& na = nodes.data[a];
        const JsonNode& nb = nodes.data[b];
        const std::string_view ka(strings.data + na.key_offset, na.key_length);
        const std::string_view kb(strings.data + nb.key_offset, nb.key_length);
        return ka < kb;
    }

    // Closes the innermost container: moves its children from scratch into children.
    Result closeContainer() {
        const Frame frame = stack.data[stack.size - 1];
        const size_t child_count = scratch.size - frame.scratch_begin;
        if (children.size + child_count > 0xFFFFFFFFu) return Result::JsonTooLarge;
        JsonNode& node = nodes.data[frame.node];
        node.first = uint32_t(children.size);
        node.count = uint32_t(child_count);
        if (!children.append(allocator, scratch.data + frame.scratch_begin, child_count)) return Result::OutOfMemory;
        if (node.type == JsonType::Object && child_count > 1) {
            // Sort the scratch copy (document order is kept in children) to find duplicate keys in
            // O(n log n): a hostile object with many keys must not cost O(n^2).
            uint32_t* begin = scratch.data + frame.scratch_begin;
            uint32_t* end = scratch.data + scratch.size;
            std::sort(begin, end, [this](uint32_t a, uint32_t b) { return keyLess(a, b); });
            for (uint32_t* it = begin + 1; it < end; ++it) {
                if (!keyLess(it[-1], it[0])) return Result::BadJson;
            }
        }
        scratch.size = frame.scratch_begin;
        --stack.size;
        return Result::Ok;
    }

    Result parseMemberKey(uint32_t* key_offset, uint32_t* key_length) {
        skipSpace();
        if (pos >= size || text[pos] != '"') return Result::BadJson;
        Result r = parseString(key_offset, key_length);
        if (r != Result::Ok) return r;
        skipSpace();
        if (pos >= size || text[pos] != ':') return Result::BadJson;
        ++pos;
        return Result::Ok;
    }

    Result run() {
        // Size the arrays from the input once (glTF JSON averages 10-15 bytes per value), so large
        // documents are not copied through many doublings; the estimate is capped by the limits.
        const size_t node_estimate = std::min<size_t>(size / 16 + 16, max_nodes);
        if (!nodes.reserve(allocator, node_estimate) || !children.reserve(allocator, node_estimate) ||
            !strings.reserve(allocator, size / 4 + 16))
            return Result::OutOfMemory;
        if (size >= 3 && std::memcmp(text, "\xEF\xBB\xBF", 3) == 0) pos = 3;
        Result r = parseValue(UINT32_MAX, 0);
        if (r != Result::Ok) return r;
        bool just_opened = stack.size > 0;
        while (stack.size > 0) {
            skipSpace();
            if (pos >= size) return Result::BadJson;
            const JsonType parent = nodes.data[stack.data[stack.size - 1].node].type;
            const char close = parent == JsonType::Object ? '}' : ']';
            const char c = text[pos];
            if (c == close) {
                ++pos;
                r = closeContainer();
                if (r != Result::Ok) return r;
                just_opened = false;
                continue;
            }
            if (!just_opened) {
                if (c != ',') return Result::BadJson;
                ++pos;
            }
            uint32_t key_offset = UINT32_MAX, key_length = 0;
            if (parent == JsonType::Object) {
                r = parseMemberKey(&key_offset, &key_length);
                if (r != Result::Ok) return r;
            }
            const size_t depth_before = stack.size;
            r = parseValue(key_offset, key_length);
            if (r != Result::Ok) return r;
            just_opened = stack.size > depth_before;
        }
        skipSpace();
        if (pos != size) return Result::BadJson;
        return Result::Ok;
    }
};

// ---- JsonValue

JsonType JsonValue::type() const {
    if (!document_ || index_ >= document_->node_count_) return JsonType::Invalid;
    return document_->nodes_[index_].type;
}

double JsonValue::number() const {
    return type() == JsonType::Number ? document_->nodes_[index_].number : 0.0;
}

bool JsonValue::asUint64(uint64_t* out) const {
    if (type() != JsonType::Number) return false;
    const double value = document_->nodes_[index_].number;
    if (!(value >= 0.0) || value > 9007199254740992.0) return false;
    const uint64_t integer = uint64_t(value);
    if (double(integer) != value) return false;
    *out = integer;
    return true;
}

std::string_view JsonValue::string() const {
    if (type() != JsonType::String) return {};
    const JsonNode& node = document_->nodes_[index_];
    return std::string_view(document_->strings_ + node.first, node.count);
}

uint32_t JsonValue::size() const {
    const JsonType t = type();
    return t == JsonType::Array || t == JsonType::Object ? document_->nodes_[index_].count : 0;
}

JsonValue JsonValue::at(uint32_t i) const {
    if (i >= size()) return JsonValue();
    return JsonValue(document_, document_->children_[document_->nodes_[index_].first + i]);
}

std::string_view JsonValue::keyAt(uint32_t i) const {
    if (type() != JsonType::Object || i >= size()) return {};
    const JsonNode& child = document_->nodes_[document_->children_[document_->nodes_[index_].first + i]];
    return std::string_view(document_->strings_ + child.key_offset, child.key_length);
}

JsonValue JsonValue::find(std::string_view key) const {
    if (type() != JsonType::Object) return JsonValue();
    const uint32_t n = size();
    for (uint32_t i = 0; i < n; ++i) {
        if (keyAt(i) == key) return at(i);
    }
    return JsonValue();
}

// ---- JsonDocument

JsonDocument::~JsonDocument() {
    release();
}

JsonDocument::JsonDocument(JsonDocument&& other) noexcept {
    *this = static_cast<JsonDocument&&>(other);
}

JsonDocument& JsonDocument::operator=(JsonDocument&& other) noexcept {
    if (this == &other) return *this;
    release();
    allocator_ = other.allocator_;
    nodes_ = other.nodes_;
    node_count_ = other.node_count_;
    children_ = other.children_;
    children_count_ = other.children_count_;
    strings_ = other.strings_;
    strings_size_ = other.strings_size_;
    other.nodes_ = nullptr;
    other.children_ = nullptr;
    other.strings_ = nullptr;
    other.node_count_ = other.children_count_ = 0;
    other.strings_size_ = 0;
    return *this;
}

void JsonDocument::release() {
    detail::deallocateBytes(allocator_, nodes_);
    detail::deallocateBytes(allocator_, children_);
    detail::deallocateBytes(allocator_, strings_);
    nodes_ = nullptr;
    children_ = nullptr;
    strings_ = nullptr;
    node_count_ = children_count_ = 0;
    strings_size_ = 0;
}

size_t JsonDocument::memoryBytes() const {
    return size_t(node_count_) * sizeof(JsonNode) + size_t(children_count_) * sizeof(uint32_t) + strings_size_;
}

Result parseJson(const char* text, size_t size, const Allocator* allocator, const JsonLimits* limits, JsonDocument* out,
                 JsonError* error) {
    if (!out || (!text && size > 0)) return Result::InvalidArgument;
    JsonParser::clear(out);
    if (error) error->offset = 0;
    JsonParser parser{};
    parser.text = text ? text : "";
    parser.size = size;
    parser.allocator = allocator ? *allocator : Allocator();
    const JsonLimits lim = limits ? *limits : JsonLimits();
    parser.max_depth = lim.max_depth ? lim.max_depth : kDefaultMaxDepth;
    parser.max_nodes = lim.max_nodes ? lim.max_nodes : kDefaultMaxNodes;
    parser.max_string_length = lim.max_string_length ? lim.max_string_length : kDefaultMaxStringLength;
    const Result result = parser.run();
    if (result != Result::Ok) {
        if (error) error->offset = parser.pos < size ? parser.pos : size;
        return result;
    }
    parser.moveInto(out);
    return Result::Ok;
}

} // namespace lodrt
