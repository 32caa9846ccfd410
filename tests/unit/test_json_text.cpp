// The META text check (libvff/src/container/json_text.h): spec/format.md section 9 and rule 8001 decide
// each case below.
#include <gtest/gtest.h>

#include <string>

#include "container/json_text.h"  // private: the META check behind rule 8001
#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace vff::detail {
namespace {

using namespace std::string_literals;

std::string problem(const std::string& text) { return checkJsonText(text, 64).problem; }

TEST(JsonText, AcceptsObjectsWithWhitespaceAround) {
  const auto r = checkJsonText(" \t\r\n{\"a\" : [1, 2.5e-3, true, false, null, \"x\"]}\n ", 64);
  EXPECT_EQ(r.problem, "");
  EXPECT_TRUE(r.isObject);
  EXPECT_FALSE(checkJsonText("[1,2]", 64).isObject);
  EXPECT_EQ(checkJsonText("[1,2]", 64).problem, "");
}

TEST(JsonText, RejectsBytesAfterTheValue) {
  EXPECT_EQ(problem("{\"a\":1}\0garbage"s), "8 bytes follow the JSON value at byte 7");
  EXPECT_EQ(problem("{\"a\":1}\0\0\0\0"s), "4 bytes follow the JSON value at byte 7");
  EXPECT_EQ(problem("{\"a\":1} x"), "1 bytes follow the JSON value at byte 8");
  EXPECT_EQ(problem("{\"a\":1}{}"), "2 bytes follow the JSON value at byte 7");
}

TEST(JsonText, RejectsAByteOrderMark) {
  EXPECT_EQ(problem("\xEF\xBB\xBF{\"a\":1}"), "begins with a UTF-8 byte-order mark (RFC 8259 section 8.1 forbids it)");
}

TEST(JsonText, RejectsLoneSurrogateEscapes) {
  EXPECT_EQ(problem(R"({"a":"\ud800"})"), "a high surrogate escape without a low surrogate after it at byte 6");
  EXPECT_EQ(problem(R"({"a":"\uDBFFx"})"), "a high surrogate escape without a low surrogate after it at byte 6");
  EXPECT_EQ(problem(R"({"a":"\ud800\u0041"})"), "a high surrogate escape without a low surrogate after it at byte 6");
  EXPECT_EQ(problem(R"({"a":"\udc00\ud800"})"), "a low surrogate escape without a high surrogate before it at byte 6");
  EXPECT_EQ(problem(R"({"a":"\ud83d\ude00 \u0000 \u00e9"})"), "");
}

TEST(JsonText, AcceptsNumbersOfAnyMagnitude) {
  EXPECT_EQ(problem(R"({"big":1e400,"neg":-1E+400,"tiny":1e-400,"long":123456789012345678901234567890})"), "");
  EXPECT_EQ(problem(R"({"a":01})"), "a number has a leading zero at byte 6");
  EXPECT_EQ(problem(R"({"a":1.})"), "a number lacks a digit at byte 7");
  EXPECT_EQ(problem(R"({"a":1e})"), "a number lacks a digit at byte 7");
  EXPECT_EQ(problem(R"({"a":-})"), "a number lacks a digit at byte 6");
  EXPECT_EQ(problem(R"({"a":+1})"), "unexpected byte 0x2B at byte 5");
}

TEST(JsonText, RejectsInvalidUtf8AndControlCharacters) {
  EXPECT_EQ(problem("{\"a\":\"\xC3\x28\"}"), "invalid UTF-8 sequence at byte 6");
  EXPECT_EQ(problem("{\"a\":\"\xC0\xAF\"}"), "invalid UTF-8 lead byte 0xC0 at byte 6");             // overlong
  EXPECT_EQ(problem("{\"a\":\"\xED\xA0\x80\"}"), "invalid UTF-8 sequence at byte 6");               // surrogate
  EXPECT_EQ(problem("{\"a\":\"\xF4\x90\x80\x80\"}"), "invalid UTF-8 sequence at byte 6");           // above U+10FFFF
  EXPECT_EQ(problem("{\"a\":\"\xC3\xA9\xF0\x9F\x98\x80\"}"), "");
  EXPECT_EQ(problem("{\"a\":\"\t\"}"), "unescaped control character 0x09 at byte 6");
  EXPECT_EQ(problem("{\"a\":\"\\x\"}"), "invalid escape 0x78 at byte 7");
}

TEST(JsonText, RejectsBrokenStructure) {
  EXPECT_EQ(problem(""), "the text ends where a value is expected at byte 0");
  EXPECT_EQ(problem("{"), "the text ends where an object key is expected at byte 1");
  EXPECT_EQ(problem("{\"a\" 1}"), "expected ':', found 0x31 at byte 5");
  EXPECT_EQ(problem("{\"a\":1,}"), "expected a string key, found 0x7D at byte 7");
  EXPECT_EQ(problem("[1,]"), "unexpected byte 0x5D at byte 3");
  EXPECT_EQ(problem("[1 2]"), "expected ',' or ']', found 0x32 at byte 3");
  EXPECT_EQ(problem("{\"a\":[1}"), "expected ',' or ']', found 0x7D at byte 7");
  EXPECT_EQ(problem("{\"a\":tru}"), "unexpected byte 0x74 at byte 5");
  EXPECT_EQ(problem("{\"a\":\"x"), "the text ends inside a string at byte 7");
  EXPECT_EQ(problem("{}"), "");
  EXPECT_EQ(problem("{\"a\":{},\"b\":[]}"), "");
}

TEST(JsonText, LimitsTheNesting) {
  const std::string ok = "{\"a\":" + std::string(63, '[') + std::string(63, ']') + "}";
  const std::string deep = "{\"a\":" + std::string(64, '[') + std::string(64, ']') + "}";
  EXPECT_EQ(problem(ok), "");
  EXPECT_EQ(problem(deep), "arrays/objects nest deeper than 64 levels at byte 68");
  // Far deeper than any stack would allow a recursive parser: still a clean answer.
  EXPECT_EQ(problem(std::string(1000000, '[')), "arrays/objects nest deeper than 64 levels at byte 64");
}

// The writer canonicalises META with nlohmann::json, which holds numbers only within binary64: it
// refuses such valid text as unsupported (not 8002, as if the text were not an object), naming the
// reason, and text that is not JSON as 8001.
TEST(JsonText, WriterRefusesMetadataItCannotHoldAsMetadataJson) {
  const FieldDesc f = vff::test::smallField(DistanceEncoding::kUnorm8Diameter);
  WriteOptions wo;
  wo.metadataJson = R"({"big":1e400})";
  const auto big = Writer::createInMemory(f, wo);
  ASSERT_FALSE(big.ok());
  EXPECT_EQ(big.error().code, Code::kUnsupported);
  EXPECT_NE(big.error().message.find("binary64"), std::string::npos) << big.error().message;
  wo.metadataJson = "{\"a\":";
  EXPECT_EQ(Writer::createInMemory(f, wo).error().code, Code::kMetadataJson);
  wo.metadataJson = "[1,2]";
  EXPECT_EQ(Writer::createInMemory(f, wo).error().code, Code::kMetadataNotObject);
}

}  // namespace
}  // namespace vff::detail
