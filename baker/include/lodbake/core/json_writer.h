#pragma once
// A small streaming JSON writer for reports (`--json` outputs). Keys appear in the order written, so
// callers write them in a fixed order and output is deterministic. Numbers use the shortest form
// that round-trips; non-finite numbers are written as null.

#include <cstdint>
#include <string>
#include <vector>

namespace lodbake {

class JsonWriter {
public:
    explicit JsonWriter(int indent = 2) : indent_(indent) {}

    JsonWriter& beginObject();
    JsonWriter& endObject();
    JsonWriter& beginArray();
    JsonWriter& endArray();
    JsonWriter& key(const std::string& k); // inside an object, before each value

    JsonWriter& value(const std::string& s);
    JsonWriter& value(const char* s) { return value(std::string(s)); }
    JsonWriter& value(double d);
    JsonWriter& value(float f) { return value(double(f)); }
    JsonWriter& value(int64_t i);
    JsonWriter& value(uint64_t u);
    JsonWriter& value(int i) { return value(int64_t(i)); }
    JsonWriter& value(unsigned u) { return value(uint64_t(u)); }
    JsonWriter& value(bool b);
    JsonWriter& null();

    template <class T> JsonWriter& field(const std::string& k, const T& v) { return key(k).value(v); }

    /// The document so far, with a trailing newline once the outermost value is closed.
    const std::string& str() const { return out_; }

    static std::string escape(const std::string& s);
    static std::string formatNumber(double d);

private:
    void beforeValue();
    void newline();
    std::string out_;
    std::vector<bool> has_items_; // per open container
    bool after_key_ = false;
    int indent_;
};

} // namespace lodbake
