// parse_json_text / parse_json_file (runtime/core/json_reader.h): every error nlohmann can raise
// is a content error with the file, line and column; nothing throws.
#include "runtime/core/json_reader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/test_tmp.h"

namespace kaskad {
namespace {

namespace fs = std::filesystem;
using json_reader::parse_json_file;
using json_reader::parse_json_text;

TEST(JsonReader, NumberOverflowIsAContentErrorWithLineAndColumn) {
  auto doc = parse_json_text("{\n  \"a\": [1,\n    1e999 ] }", "x.json");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.error().file, "x.json");
  EXPECT_EQ(doc.error().where, "line 3, column 9");  // the number's last character, as nlohmann counts
  EXPECT_NE(doc.error().message.find("number overflow parsing '1e999'"), std::string::npos)
      << doc.error().message;
  EXPECT_EQ(doc.error().message.find("[json.exception"), std::string::npos) << doc.error().message;
}

// One depth limit for every JSON: kMaxDepth levels read, one more is an error at the bracket
// too deep (line and column), long before a recursive walk could overflow the stack; brackets
// in strings do not count.
TEST(JsonReader, NestingDeeperThanTheLimitIsRefusedWhereItStarts) {
  const int limit = json_reader::kMaxDepth;
  const auto nested = [](int depth) {
    return "{\"a\":\n" + std::string(std::size_t(depth - 1), '[') + "\"[[[{{{\"" +
           std::string(std::size_t(depth - 1), ']') + "}";
  };
  EXPECT_TRUE(parse_json_text(nested(limit), "ok.json").ok());
  auto deep = parse_json_text(nested(limit + 1), "deep.json");
  ASSERT_FALSE(deep.ok());
  EXPECT_EQ(deep.error().file, "deep.json");
  EXPECT_EQ(deep.error().where, "line 2, column " + std::to_string(limit));
  EXPECT_NE(deep.error().message.find("nested deeper than " + std::to_string(limit) + " levels"),
            std::string::npos)
      << deep.error().message;
  // A hundred thousand levels: refused as quickly, nothing recurses.
  const std::string huge = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_FALSE(parse_json_text(huge, "huge.json").ok());
  EXPECT_FALSE(json_reader::check_depth(huge, "--set").ok());
}

// A value quoted in a message is cut when long: a number of thousands of digits names its length.
TEST(JsonReader, LongValuesInMessagesAreCut) {
  EXPECT_EQ(json_reader::quote("1e999"), "'1e999'");
  const std::string digits(5000, '9');
  EXPECT_EQ(json_reader::quote(digits), "'" + std::string(32, '9') + "...' (5000 characters)");
  auto doc = parse_json_text("[" + digits + "]", "digits.json");
  ASSERT_FALSE(doc.ok());
  EXPECT_NE(doc.error().message.find("number overflow parsing '9999"), std::string::npos)
      << doc.error().message;
  EXPECT_LT(doc.error().message.size(), 200u) << doc.error().message;
}

TEST(JsonReader, SyntaxErrorsAndBadBytesAreShownPrintably) {
  auto doc = parse_json_text("{ \"k\": \"\xff\xfe\" }", "y.json");
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.error().where, "line 1, column 9");
  EXPECT_NE(doc.error().message.find("\\xFF"), std::string::npos) << doc.error().message;
  for (const char c : doc.error().to_string()) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << int(c);
}

TEST(JsonReader, FoldersMissingAndEmptyFiles) {
  const fs::path dir = testing_util::test_tmp("json_reader");
  fs::remove_all(dir);
  fs::create_directories(dir / "folder.json");
  std::ofstream(dir / "empty.json").close();
  auto folder = parse_json_file(dir / "folder.json");
  ASSERT_FALSE(folder.ok());
  EXPECT_NE(folder.error().message.find("directory"), std::string::npos) << folder.error().message;
  auto missing = parse_json_file(dir / "missing.json");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("cannot open"), std::string::npos);
  auto empty = parse_json_file(dir / "empty.json");
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().where, "line 1, column 1");
}

TEST(JsonParse, AKeyGivenTwiceInOneObjectIsAnErrorAtItsPointer) {
  // nlohmann keeps the last of two equal keys without a word: a scene saying "shadow" twice
  // lost the first block's settings silently.
  auto top = parse_json_text(R"({"a": 1, "b": 2, "a": 3})", "x.json");
  ASSERT_FALSE(top.ok());
  EXPECT_EQ(top.error().where, "/a");
  EXPECT_NE(top.error().message.find("'a' is given twice"), std::string::npos);
  auto deep = parse_json_text(R"({"t": [{"k": 1}, {"k": 1, "m/~": {}, "m/~": 2}]})", "x.json");
  ASSERT_FALSE(deep.ok());
  EXPECT_EQ(deep.error().where, "/t/1/m~1~0");
  // Equal keys in different objects, and equal values, are fine.
  auto fine =
      parse_json_text(R"({"a": {"a": 1}, "b": [{"a": 1}, {"a": 1}], "c": ["a", "a"]})", "x.json");
  ASSERT_TRUE(fine.ok()) << fine.error().to_string();
  EXPECT_EQ((*fine)["b"][1]["a"], 1);
}

}  // namespace
}  // namespace kaskad
