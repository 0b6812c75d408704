#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodrt/json.h"

using lodrt::JsonDocument;
using lodrt::JsonError;
using lodrt::JsonLimits;
using lodrt::JsonType;
using lodrt::JsonValue;
using lodrt::Result;

namespace {

Result parse(const std::string& text, JsonDocument* doc, const JsonLimits* limits = nullptr,
             JsonError* error = nullptr) {
    return lodrt::parseJson(text.data(), text.size(), nullptr, limits, doc, error);
}

Result parseOnly(const std::string& text) {
    JsonDocument doc;
    return parse(text, &doc);
}

// Counts live allocations and can fail the n-th one (n counts from 1; 0 never fails).
struct CountingHeap {
    long live = 0;
    long total = 0;
    long fail_at = 0;
    static void* allocate(void* user, size_t size) {
        auto* heap = static_cast<CountingHeap*>(user);
        ++heap->total;
        if (heap->fail_at && heap->total == heap->fail_at) return nullptr;
        ++heap->live;
        return std::malloc(size);
    }
    static void deallocate(void* user, void* ptr) {
        --static_cast<CountingHeap*>(user)->live;
        std::free(ptr);
    }
    lodrt::Allocator allocator() {
        lodrt::Allocator a;
        a.allocate = &allocate;
        a.deallocate = &deallocate;
        a.user = this;
        return a;
    }
};

const char* const kSampleDoc =
    R"({"name":"caf\u00e9 \ud83d\ude00","n":[0,-1,2.5,1e3,-0.25E-2],"t":true,"f":false,"z":null,)"
    R"("o":{"a":{},"b":[],"c":"\"\\\/\b\f\n\r\t"},"s":"\u0000x"})";

} // namespace

TEST(JsonTest, ParsesAllValueTypes) {
    JsonDocument doc;
    ASSERT_EQ(parse(kSampleDoc, &doc), Result::Ok);
    const JsonValue root = doc.root();
    ASSERT_TRUE(root.isObject());
    EXPECT_EQ(root.size(), 7u);
    EXPECT_EQ(root.find("name").string(), "caf\xC3\xA9 \xF0\x9F\x98\x80");
    const JsonValue n = root.find("n");
    ASSERT_EQ(n.size(), 5u);
    EXPECT_EQ(n.at(0).number(), 0.0);
    EXPECT_EQ(n.at(1).number(), -1.0);
    EXPECT_EQ(n.at(2).number(), 2.5);
    EXPECT_EQ(n.at(3).number(), 1000.0);
    EXPECT_EQ(n.at(4).number(), -0.0025);
    EXPECT_EQ(root.find("t").type(), JsonType::True);
    EXPECT_TRUE(root.find("t").boolean());
    EXPECT_EQ(root.find("f").type(), JsonType::False);
    EXPECT_EQ(root.find("z").type(), JsonType::Null);
    const JsonValue o = root.find("o");
    EXPECT_TRUE(o.find("a").isObject());
    EXPECT_EQ(o.find("a").size(), 0u);
    EXPECT_TRUE(o.find("b").isArray());
    EXPECT_EQ(o.find("c").string(), "\"\\/\b\f\n\r\t");
    EXPECT_EQ(root.find("s").string(), std::string("\0x", 2));
    EXPECT_EQ(doc.nodeCount(), 16u);
    EXPECT_GT(doc.memoryBytes(), 0u);
}

TEST(JsonTest, MembersKeepDocumentOrder) {
    JsonDocument doc;
    ASSERT_EQ(parse(R"({"zeta":1,"alpha":2,"mid":[3,4]})", &doc), Result::Ok);
    const JsonValue root = doc.root();
    EXPECT_EQ(root.keyAt(0), "zeta");
    EXPECT_EQ(root.keyAt(1), "alpha");
    EXPECT_EQ(root.keyAt(2), "mid");
    EXPECT_EQ(root.at(1).number(), 2.0);
    EXPECT_EQ(root.at(2).at(1).number(), 4.0);
    EXPECT_EQ(root.keyAt(3), "");
}

TEST(JsonTest, MissingLookupsReturnInvalidValues) {
    JsonDocument doc;
    ASSERT_EQ(parse(R"({"a":[1]})", &doc), Result::Ok);
    const JsonValue root = doc.root();
    EXPECT_FALSE(root.find("b").isValid());
    EXPECT_FALSE(root.find("a").at(1).isValid());
    EXPECT_FALSE(root.find("a").find("x").isValid());
    EXPECT_FALSE(root.find("b").find("c").at(0).find("d").isValid());
    EXPECT_EQ(root.find("b").string(), "");
    EXPECT_EQ(root.find("b").number(), 0.0);
    EXPECT_EQ(JsonValue().type(), JsonType::Invalid);
    JsonDocument empty;
    EXPECT_FALSE(empty.root().isValid());
}

TEST(JsonTest, ScalarRootsAndWhitespace) {
    JsonDocument doc;
    ASSERT_EQ(parse(" \t\r\n42 \n", &doc), Result::Ok);
    EXPECT_EQ(doc.root().number(), 42.0);
    ASSERT_EQ(parse("\"x\"", &doc), Result::Ok);
    EXPECT_EQ(doc.root().string(), "x");
    ASSERT_EQ(parse("\xEF\xBB\xBF[]", &doc), Result::Ok);
    EXPECT_TRUE(doc.root().isArray());
}

TEST(JsonTest, EveryTruncatedPrefixFailsCleanly) {
    const std::string text = kSampleDoc;
    for (size_t size = 0; size < text.size(); ++size) {
        // Exact-size heap copy so ASan flags any read past the prefix.
        std::vector<char> prefix(text.begin(), text.begin() + size);
        JsonDocument doc;
        JsonError error;
        const Result result = lodrt::parseJson(size ? prefix.data() : nullptr, size, nullptr, nullptr, &doc, &error);
        EXPECT_NE(result, Result::Ok) << "prefix of " << size << " bytes";
        EXPECT_EQ(doc.nodeCount(), 0u);
        EXPECT_LE(error.offset, size);
    }
}

TEST(JsonTest, RejectsTrailingGarbage) {
    EXPECT_EQ(parseOnly("{} x"), Result::BadJson);
    EXPECT_EQ(parseOnly("{}{}"), Result::BadJson);
    EXPECT_EQ(parseOnly("[1] ,"), Result::BadJson);
    EXPECT_EQ(parseOnly(std::string("{}\0", 3)), Result::BadJson);
}

TEST(JsonTest, RejectsSyntaxErrors) {
    for (const char* text : {"",
                             " ",
                             "{",
                             "}",
                             "[1,]",
                             "[,1]",
                             "{\"a\":1,}",
                             "{\"a\" 1}",
                             "{\"a\":}",
                             "{a:1}",
                             "{'a':1}",
                             "[1 2]",
                             "tru",
                             "nul",
                             "True",
                             "[true false]",
                             "{\"a\":1 \"b\":2}",
                             "[1]]",
                             "{\"a\":[}",
                             "/* c */ {}",
                             "[\"a\"\"b\"]"}) {
        EXPECT_EQ(parseOnly(text), Result::BadJson) << text;
    }
}

TEST(JsonTest, RejectsInvalidNumbers) {
    for (const char* text : {"01", "-01", "1.", ".5", "+1", "-", "1e", "1e+", "0x10", "NaN", "Infinity", "-Infinity",
                             "1.e5", "--1", "1_000", "[1.5.2]"}) {
        EXPECT_EQ(parseOnly(text), Result::BadJson) << text;
    }
}

TEST(JsonTest, HugeNumbersAreOutOfRange) {
    EXPECT_EQ(parseOnly("[1e400]"), Result::NumberOutOfRange);
    EXPECT_EQ(parseOnly("[-1e400]"), Result::NumberOutOfRange);
    EXPECT_EQ(parseOnly("[1e-400]"), Result::NumberOutOfRange);
    EXPECT_EQ(parseOnly("[" + std::string(400, '9') + "]"), Result::NumberOutOfRange);
    JsonDocument doc;
    ASSERT_EQ(parse("[1.7976931348623157e308, 4.9e-324, 123456789012345678901234567890, 0.1, -0]", &doc), Result::Ok);
    EXPECT_EQ(doc.root().at(0).number(), 1.7976931348623157e308);
    EXPECT_EQ(doc.root().at(1).number(), 4.9e-324);
    EXPECT_EQ(doc.root().at(2).number(), 1.2345678901234568e29);
    EXPECT_EQ(doc.root().at(3).number(), 0.1);
    EXPECT_EQ(doc.root().at(4).number(), 0.0);
    const std::string long_digits = "[0." + std::string(5000, '3') + "]";
    ASSERT_EQ(parse(long_digits, &doc), Result::Ok);
    EXPECT_DOUBLE_EQ(doc.root().at(0).number(), 1.0 / 3.0);
}

TEST(JsonTest, AsUint64AcceptsOnlyExactNonNegativeIntegers) {
    JsonDocument doc;
    ASSERT_EQ(parse("[0, 7, 1e3, 9007199254740992, 9007199254740993e1, -1, 2.5, \"3\", -0]", &doc), Result::Ok);
    uint64_t v = 99;
    EXPECT_TRUE(doc.root().at(0).asUint64(&v));
    EXPECT_EQ(v, 0u);
    EXPECT_TRUE(doc.root().at(1).asUint64(&v));
    EXPECT_EQ(v, 7u);
    EXPECT_TRUE(doc.root().at(2).asUint64(&v));
    EXPECT_EQ(v, 1000u);
    EXPECT_TRUE(doc.root().at(3).asUint64(&v));
    EXPECT_EQ(v, 9007199254740992u);
    EXPECT_FALSE(doc.root().at(4).asUint64(&v));
    EXPECT_FALSE(doc.root().at(5).asUint64(&v));
    EXPECT_FALSE(doc.root().at(6).asUint64(&v));
    EXPECT_FALSE(doc.root().at(7).asUint64(&v));
    EXPECT_TRUE(doc.root().at(8).asUint64(&v));
    EXPECT_EQ(v, 0u);
}

TEST(JsonTest, RejectsInvalidEscapes) {
    for (const char* text : {R"(["\x"])", R"(["\a"])", R"(["\u12"])", R"(["\u12G4"])", R"(["\U0041"])", R"(["\)",
                             R"(["\'"])", R"(["\0"])"}) {
        EXPECT_EQ(parseOnly(text), Result::BadJson) << text;
    }
    JsonDocument doc;
    ASSERT_EQ(parse(R"(["\u0041\u00DF\u4e2D"])", &doc), Result::Ok);
    EXPECT_EQ(doc.root().at(0).string(), "A\xC3\x9F\xE4\xB8\xAD");
}

TEST(JsonTest, ValidatesSurrogatePairs) {
    JsonDocument doc;
    ASSERT_EQ(parse(R"(["\uD834\uDD1E"])", &doc), Result::Ok);
    EXPECT_EQ(doc.root().at(0).string(), "\xF0\x9D\x84\x9E");
    ASSERT_EQ(parse(R"(["\udbff\udfff"])", &doc), Result::Ok);
    EXPECT_EQ(doc.root().at(0).string(), "\xF4\x8F\xBF\xBF");
    for (const char* text : {R"(["\uD834"])", R"(["\uD834x"])", R"(["\uDD1E"])", R"(["\uD834\u0041"])",
                             R"(["\uD834\uD834"])", R"(["\uD834\n"])"}) {
        EXPECT_EQ(parseOnly(text), Result::BadUtf8) << text;
    }
}

TEST(JsonTest, ValidatesUtf8) {
    const char* const good[] = {"\x7F",         "\xC2\x80",     "\xDF\xBF",         "\xE0\xA0\x80",    "\xED\x9F\xBF",
                                "\xEE\x80\x80", "\xEF\xBF\xBF", "\xF0\x90\x80\x80", "\xF4\x8F\xBF\xBF"};
    for (const char* s : good) {
        JsonDocument doc;
        ASSERT_EQ(parse(std::string("[\"") + s + "\"]", &doc), Result::Ok) << s;
        EXPECT_EQ(doc.root().at(0).string(), s);
    }
    const char* const bad[] = {
        "\x80",             // lone continuation
        "\xBF",             // lone continuation
        "\xC0\x80",         // overlong NUL
        "\xC1\xBF",         // overlong
        "\xE0\x80\x80",     // overlong 3-byte
        "\xE0\x9F\xBF",     // overlong 3-byte
        "\xED\xA0\x80",     // UTF-16 surrogate
        "\xED\xBF\xBF",     // UTF-16 surrogate
        "\xF0\x80\x80\x80", // overlong 4-byte
        "\xF0\x8F\xBF\xBF", // overlong 4-byte
        "\xF4\x90\x80\x80", // above U+10FFFF
        "\xF5\x80\x80\x80", // invalid lead
        "\xFF",             // invalid lead
        "\xC2",             // cut off before the quote
        "\xE2\x82",         // cut off
        "\xC2\x41",         // bad continuation
        "\xE2\x28\xA1",     // bad continuation
    };
    for (const char* s : bad) EXPECT_EQ(parseOnly(std::string("[\"") + s + "\"]"), Result::BadUtf8) << s;
    // Keys are validated too, and so is a sequence cut off by the end of the input.
    EXPECT_EQ(parseOnly("{\"\xC0\xAF\":1}"), Result::BadUtf8);
    EXPECT_EQ(parseOnly("[\"\xF0\x9F\x98"), Result::BadUtf8);
}

TEST(JsonTest, RejectsRawControlCharacters) {
    EXPECT_EQ(parseOnly("[\"a\nb\"]"), Result::BadJson);
    EXPECT_EQ(parseOnly("[\"a\tb\"]"), Result::BadJson);
    EXPECT_EQ(parseOnly(std::string("[\"a\0b\"]", 7)), Result::BadJson);
    EXPECT_EQ(parseOnly("[\"a\x1F\"]"), Result::BadJson);
}

TEST(JsonTest, RejectsDuplicateKeys) {
    EXPECT_EQ(parseOnly(R"({"a":1,"a":2})"), Result::BadJson);
    EXPECT_EQ(parseOnly(R"({"a":1,"b":2,"c":3,"b":{}})"), Result::BadJson);
    EXPECT_EQ(parseOnly(R"({"x":{"k":1,"k":1}})"), Result::BadJson);
    EXPECT_EQ(parseOnly(R"({"a":1,"\u0061":2})"), Result::BadJson);         // same key after unescaping
    EXPECT_EQ(parseOnly(R"({"a":{"a":{"a":1}},"b":{"a":2}})"), Result::Ok); // same key, different objects
    EXPECT_EQ(parseOnly(R"({"a":1,"a ":2,"A":3,"":4})"), Result::Ok);
    // Many keys: the check is O(n log n), and a duplicate at the end is still found.
    std::string many = "{";
    for (int i = 0; i < 20000; ++i) many += "\"k" + std::to_string(i) + "\":" + std::to_string(i) + ",";
    JsonDocument doc;
    ASSERT_EQ(parse(many + "\"end\":0}", &doc), Result::Ok);
    EXPECT_EQ(doc.root().find("k19999").number(), 19999.0);
    EXPECT_EQ(parseOnly(many + "\"k7\":0}"), Result::BadJson);
}

TEST(JsonTest, RefusesDeepNesting) {
    auto nested = [](int depth) { return std::string(size_t(depth), '[') + std::string(size_t(depth), ']'); };
    EXPECT_EQ(parseOnly(nested(64)), Result::Ok);
    EXPECT_EQ(parseOnly(nested(65)), Result::JsonTooDeep);
    EXPECT_EQ(parseOnly(std::string(1000000, '[')), Result::JsonTooDeep);
    std::string objects;
    for (int i = 0; i < 100; ++i) objects += "{\"a\":";
    EXPECT_EQ(parseOnly(objects), Result::JsonTooDeep);
    JsonLimits limits;
    limits.max_depth = 3;
    JsonDocument doc;
    EXPECT_EQ(parse(nested(3), &doc, &limits), Result::Ok);
    EXPECT_EQ(parse(nested(4), &doc, &limits), Result::JsonTooDeep);
}

TEST(JsonTest, DeepNestingUsesNoRecursion) {
    // With the limit lifted, a million levels parse without exhausting the C++ stack.
    JsonLimits limits;
    limits.max_depth = 2000000;
    const int depth = 1000000;
    JsonDocument doc;
    ASSERT_EQ(parse(std::string(depth, '[') + std::string(depth, ']'), &doc, &limits), Result::Ok);
    EXPECT_EQ(doc.nodeCount(), uint32_t(depth));
}

TEST(JsonTest, EnforcesNodeAndStringLimits) {
    JsonLimits limits;
    limits.max_nodes = 4;
    JsonDocument doc;
    EXPECT_EQ(parse("[1,2,3]", &doc, &limits), Result::Ok);
    EXPECT_EQ(parse("[1,2,3,4]", &doc, &limits), Result::JsonTooLarge);
    limits = JsonLimits();
    limits.max_string_length = 5;
    EXPECT_EQ(parse(R"(["12345"])", &doc, &limits), Result::Ok);
    EXPECT_EQ(parse(R"(["123456"])", &doc, &limits), Result::JsonTooLarge);
    EXPECT_EQ(parse(R"({"123456":1})", &doc, &limits), Result::JsonTooLarge);
    EXPECT_EQ(parse(R"(["\u00e9\u00e9\u00e9"])", &doc, &limits), Result::JsonTooLarge); // 6 decoded bytes
    EXPECT_EQ(doc.nodeCount(), 0u);
}

TEST(JsonTest, ReportsErrorOffset) {
    JsonDocument doc;
    JsonError error;
    EXPECT_EQ(parse("{\"a\": [1, 2, x]}", &doc, nullptr, &error), Result::BadJson);
    EXPECT_EQ(error.offset, 13u);
    EXPECT_EQ(parse("[\"ok\", \"\xC0\x80\"]", &doc, nullptr, &error), Result::BadUtf8);
    EXPECT_EQ(error.offset, 8u);
}

TEST(JsonTest, UsesAllocatorHooksAndFreesEverything) {
    CountingHeap heap;
    const lodrt::Allocator allocator = heap.allocator();
    {
        JsonDocument doc;
        ASSERT_EQ(lodrt::parseJson(kSampleDoc, std::strlen(kSampleDoc), &allocator, nullptr, &doc), Result::Ok);
        EXPECT_GT(heap.total, 0);
        EXPECT_EQ(heap.live, 3); // nodes, children, strings
        JsonDocument moved(static_cast<JsonDocument&&>(doc));
        EXPECT_EQ(doc.nodeCount(), 0u);
        EXPECT_EQ(moved.root().find("t").type(), JsonType::True);
        EXPECT_EQ(heap.live, 3);
    }
    EXPECT_EQ(heap.live, 0);
}

TEST(JsonTest, AllocationFailureAtEveryStepIsCleanOutOfMemory) {
    CountingHeap probe;
    lodrt::Allocator allocator = probe.allocator();
    {
        JsonDocument doc;
        ASSERT_EQ(lodrt::parseJson(kSampleDoc, std::strlen(kSampleDoc), &allocator, nullptr, &doc), Result::Ok);
    }
    const long needed = probe.total;
    ASSERT_GT(needed, 0);
    for (long fail_at = 1; fail_at <= needed; ++fail_at) {
        CountingHeap heap;
        heap.fail_at = fail_at;
        allocator = heap.allocator();
        JsonDocument doc;
        EXPECT_EQ(lodrt::parseJson(kSampleDoc, std::strlen(kSampleDoc), &allocator, nullptr, &doc), Result::OutOfMemory)
            << fail_at;
        EXPECT_EQ(heap.live, 0) << fail_at;
    }
}

TEST(JsonTest, RejectsNullArguments) {
    JsonDocument doc;
    EXPECT_EQ(lodrt::parseJson("{}", 2, nullptr, nullptr, nullptr), Result::InvalidArgument);
    EXPECT_EQ(lodrt::parseJson(nullptr, 2, nullptr, nullptr, &doc), Result::InvalidArgument);
    EXPECT_EQ(lodrt::parseJson(nullptr, 0, nullptr, nullptr, &doc), Result::BadJson);
}
