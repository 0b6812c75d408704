// The JSON value tree (json_value.h).
#include "lodbake/core/json_value.h"

#include "lodbake/core/json_writer.h"

namespace lodbake {

namespace {

void write(const JsonNode& node, JsonWriter& j) {
    switch (node.kind()) {
    case JsonNode::Kind::Null:
        j.null();
        return;
    case JsonNode::Kind::Bool:
        j.value(node.asBool());
        return;
    case JsonNode::Kind::Int:
        j.value(node.asInt());
        return;
    case JsonNode::Kind::UInt:
        j.value(node.asUInt());
        return;
    case JsonNode::Kind::Double:
        j.value(node.asDouble());
        return;
    case JsonNode::Kind::String:
        j.value(node.asString());
        return;
    case JsonNode::Kind::Array:
        j.beginArray();
        for (const JsonNode& item : node.items()) write(item, j);
        j.endArray();
        return;
    case JsonNode::Kind::Object:
        j.beginObject();
        for (const auto& member : node.members()) {
            j.key(member.first);
            write(member.second, j);
        }
        j.endObject();
        return;
    }
}

} // namespace

JsonNode& JsonNode::set(const std::string& key, JsonNode value) {
    for (auto& member : members_)
        if (member.first == key) {
            member.second = std::move(value);
            return *this;
        }
    members_.emplace_back(key, std::move(value));
    return *this;
}

JsonNode& JsonNode::push(JsonNode value) {
    items_.push_back(std::move(value));
    return *this;
}

const JsonNode* JsonNode::find(const std::string& key) const {
    for (const auto& member : members_)
        if (member.first == key) return &member.second;
    return nullptr;
}

std::string JsonNode::text(int indent) const {
    JsonWriter j(indent);
    write(*this, j);
    return j.str();
}

bool operator==(const JsonNode& a, const JsonNode& b) {
    if (a.kind_ != b.kind_) return false;
    switch (a.kind_) {
    case JsonNode::Kind::Null:
        return true;
    case JsonNode::Kind::Bool:
        return a.bool_ == b.bool_;
    case JsonNode::Kind::Int:
        return a.int_ == b.int_;
    case JsonNode::Kind::UInt:
        return a.uint_ == b.uint_;
    case JsonNode::Kind::Double:
        return a.double_ == b.double_ || (a.double_ != a.double_ && b.double_ != b.double_);
    case JsonNode::Kind::String:
        return a.string_ == b.string_;
    case JsonNode::Kind::Array:
        return a.items_ == b.items_;
    case JsonNode::Kind::Object:
        return a.members_ == b.members_;
    }
    return false;
}

} // namespace lodbake
