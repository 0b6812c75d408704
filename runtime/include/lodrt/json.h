#pragma once
// Strict JSON (RFC 8259) parser into a compact read-only DOM, for glTF documents that may be hostile.
// Non-recursive: an explicit stack bounded by JsonLimits::max_depth. All memory comes from the
// document's Allocator hooks. Decisions beyond the RFC:
// - duplicate keys in one object are an error (BadJson): two readers must never see different values;
// - numbers are doubles; a number that overflows or underflows a double is NumberOutOfRange;
// - strings must be valid UTF-8 (no overlongs, no surrogates, nothing above U+10FFFF) and \u escapes
//   must pair surrogates correctly (BadUtf8); raw control characters in strings are BadJson;
// - one leading UTF-8 byte order mark is skipped; anything but whitespace after the value is BadJson.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "lodrt/allocator.h"
#include "lodrt/export.h"
#include "lodrt/result.h"

namespace lodrt {

/// Zero means "default" for every field.
struct JsonLimits {
    uint32_t max_depth = 0;         // deepest nesting of arrays/objects; default 64
    uint32_t max_nodes = 0;         // values in the document (keys not counted); default 1 << 22
    uint32_t max_string_length = 0; // bytes of one decoded string or key; default 1 << 26
};

enum class JsonType : uint8_t { Invalid, Null, False, True, Number, String, Array, Object };

class JsonDocument;

/// A handle to one value of a JsonDocument (a document pointer and an index); cheap to copy, valid
/// while the document lives. Lookups on a missing value or wrong type return an invalid JsonValue
/// (type() == Invalid), so chains like doc.root().find("asset").find("version") never crash.
class LODRT_API JsonValue {
public:
    JsonValue() = default;
    JsonType type() const;
    bool isValid() const { return type() != JsonType::Invalid; }
    bool isNumber() const { return type() == JsonType::Number; }
    bool isString() const { return type() == JsonType::String; }
    bool isArray() const { return type() == JsonType::Array; }
    bool isObject() const { return type() == JsonType::Object; }
    bool isBool() const { return type() == JsonType::True || type() == JsonType::False; }

    /// The number, or 0 when not a number.
    double number() const;
    /// true for the literal true; false otherwise.
    bool boolean() const { return type() == JsonType::True; }
    /// Stores the number in *out and returns true when it is an integer in [0, 2^53]; false otherwise.
    bool asUint64(uint64_t* out) const;
    /// The decoded UTF-8 string (NUL-terminated in memory), or empty when not a string.
    std::string_view string() const;

    /// Number of elements (array) or members (object); 0 for anything else.
    uint32_t size() const;
    /// Element i of an array or the value of member i of an object, in document order; O(1).
    JsonValue at(uint32_t i) const;
    /// The key of member i of an object; empty when out of range or not an object.
    std::string_view keyAt(uint32_t i) const;
    /// The value of the member named key (linear in the member count), or invalid when absent.
    JsonValue find(std::string_view key) const;

    /// Index of this value in the document (pre-order); useful as a stable id.
    uint32_t index() const { return index_; }

private:
    friend class JsonDocument;
    JsonValue(const JsonDocument* document, uint32_t index) : document_(document), index_(index) {}
    const JsonDocument* document_ = nullptr;
    uint32_t index_ = 0;
};

namespace detail {
struct JsonNode;
}

/// Owns the DOM of one parsed document. Move-only; frees through the allocator it was parsed with.
class LODRT_API JsonDocument {
public:
    JsonDocument() = default;
    ~JsonDocument();
    JsonDocument(JsonDocument&& other) noexcept;
    JsonDocument& operator=(JsonDocument&& other) noexcept;
    JsonDocument(const JsonDocument&) = delete;
    JsonDocument& operator=(const JsonDocument&) = delete;

    /// The top-level value; invalid when nothing has been parsed.
    JsonValue root() const { return node_count_ > 0 ? JsonValue(this, 0) : JsonValue(); }
    /// Values in the document.
    uint32_t nodeCount() const { return node_count_; }
    /// Bytes held by the DOM.
    size_t memoryBytes() const;

private:
    friend class JsonValue;
    friend struct JsonParser;
    void release();
    Allocator allocator_;
    detail::JsonNode* nodes_ = nullptr;
    uint32_t node_count_ = 0;
    uint32_t* children_ = nullptr; // child node indices, contiguous per container
    uint32_t children_count_ = 0;
    char* strings_ = nullptr; // decoded strings and keys, each NUL-terminated
    size_t strings_size_ = 0;
};

/// Where parsing stopped.
struct JsonError {
    size_t offset = 0; // byte offset into the input of the offending character
};

/// Parses text[0, size) into *out (replacing what it held). allocator and limits may be null for
/// defaults. On failure *out is empty, and *error (if not null) gets the byte offset.
/// Returns Ok, BadJson, BadUtf8, JsonTooDeep, JsonTooLarge, NumberOutOfRange, OutOfMemory, or
/// InvalidArgument (out null, or text null with size > 0). Empty input is BadJson.
LODRT_API Result parseJson(const char* text, size_t size, const Allocator* allocator, const JsonLimits* limits,
                           JsonDocument* out, JsonError* error = nullptr);

} // namespace lodrt
