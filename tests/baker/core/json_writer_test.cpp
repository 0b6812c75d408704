#include "lodbake/core/json_writer.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

using namespace lodbake;

TEST(JsonWriterTest, NestedDocument) {
    JsonWriter j(0);
    j.beginObject().field("a", 1).key("b").beginArray().value(true).value("x\"y").null().endArray();
    j.key("c").beginObject().endObject().endObject();
    EXPECT_EQ(j.str(), "{\"a\":1,\"b\":[true,\"x\\\"y\",null],\"c\":{}}\n");
}

TEST(JsonWriterTest, IndentedDocument) {
    JsonWriter j(2);
    j.beginObject().field("a", 1).key("b").beginArray().value(2).endArray().endObject();
    EXPECT_EQ(j.str(), "{\n  \"a\": 1,\n  \"b\": [\n    2\n  ]\n}\n");
}

TEST(JsonWriterTest, NumbersRoundTripShortest) {
    EXPECT_EQ(JsonWriter::formatNumber(0.1), "0.1");
    EXPECT_EQ(JsonWriter::formatNumber(1e-5), "1e-05");
    EXPECT_EQ(JsonWriter::formatNumber(-0.0), "0");
    EXPECT_EQ(JsonWriter::formatNumber(std::numeric_limits<double>::infinity()), "null");
    EXPECT_EQ(JsonWriter::formatNumber(std::nan("")), "null");
    const double v = 0.1234567890123456789;
    EXPECT_EQ(std::strtod(JsonWriter::formatNumber(v).c_str(), nullptr), v);
}

TEST(JsonWriterTest, EscapesControlCharacters) {
    EXPECT_EQ(JsonWriter::escape(std::string("a\x01\n\\", 4)), "\"a\\u0001\\n\\\\\"");
}
