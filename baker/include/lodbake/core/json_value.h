#pragma once
// A small JSON value tree: structured data that a writer serialises without going through text
// (the pack's extension objects, written into the glTF document by the gltf module). Objects keep
// their members in insertion order; numbers keep the type they were given (signed, unsigned or
// double), so a serialiser can write each as the JsonWriter would.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lodbake {

class JsonNode {
public:
    enum class Kind { Null, Bool, Int, UInt, Double, String, Array, Object };

    JsonNode() = default;
    JsonNode(bool b) : kind_(Kind::Bool), bool_(b) {}
    JsonNode(int i) : kind_(Kind::Int), int_(i) {}
    JsonNode(int64_t i) : kind_(Kind::Int), int_(i) {}
    JsonNode(unsigned u) : kind_(Kind::UInt), uint_(u) {}
    JsonNode(uint64_t u) : kind_(Kind::UInt), uint_(u) {}
    JsonNode(double d) : kind_(Kind::Double), double_(d) {}
    JsonNode(std::string s) : kind_(Kind::String), string_(std::move(s)) {}
    JsonNode(const char* s) : kind_(Kind::String), string_(s) {}

    static JsonNode object() { return JsonNode(Kind::Object); }
    static JsonNode array() { return JsonNode(Kind::Array); }

    Kind kind() const { return kind_; }
    bool isObject() const { return kind_ == Kind::Object; }
    bool isArray() const { return kind_ == Kind::Array; }
    bool asBool() const { return bool_; }
    int64_t asInt() const { return int_; }
    uint64_t asUInt() const { return uint_; }
    double asDouble() const { return double_; }
    const std::string& asString() const { return string_; }

    /// Object: sets member `key` (replacing an existing one in place, else appending). Returns *this.
    JsonNode& set(const std::string& key, JsonNode value);
    /// Array: appends `value`. Returns *this.
    JsonNode& push(JsonNode value);
    /// Object: the member `key`, or null when absent.
    const JsonNode* find(const std::string& key) const;

    const std::vector<JsonNode>& items() const { return items_; }
    const std::vector<std::pair<std::string, JsonNode>>& members() const { return members_; }

    /// The value as JSON text (JsonWriter: members in insertion order, shortest round-trip numbers).
    std::string text(int indent = 0) const;

    friend bool operator==(const JsonNode& a, const JsonNode& b);
    friend bool operator!=(const JsonNode& a, const JsonNode& b) { return !(a == b); }

private:
    explicit JsonNode(Kind kind) : kind_(kind) {}
    Kind kind_ = Kind::Null;
    bool bool_ = false;
    int64_t int_ = 0;
    uint64_t uint_ = 0;
    double double_ = 0;
    std::string string_;
    std::vector<JsonNode> items_;
    std::vector<std::pair<std::string, JsonNode>> members_;
};

} // namespace lodbake
