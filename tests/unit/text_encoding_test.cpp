// The small text helpers several parts share: hex both ways (server/common/hex.h) and a UTF-8
// text cut without splitting a character (renderer/util/utf8_text.h).
#include <gtest/gtest.h>

#include "renderer/util/utf8_text.h"
#include "server/common/hex.h"

namespace farm {
namespace {

TEST(HexTest, BytesGoToLowercaseHexAndBack) {
  const std::string bytes("\x00\x7f\x80\xff", 4);
  EXPECT_EQ(to_hex(bytes), "007f80ff");
  EXPECT_EQ(from_hex("007f80ff"), bytes);
  EXPECT_EQ(from_hex("007F80FF"), bytes);
  EXPECT_EQ(from_hex(""), std::string());
  EXPECT_FALSE(from_hex("abc"));  // odd
  EXPECT_FALSE(from_hex("0g"));
  EXPECT_FALSE(from_hex("+1"));
  EXPECT_TRUE(is_lowercase_hex("0123456789abcdef"));
  EXPECT_TRUE(is_lowercase_hex(""));
  EXPECT_FALSE(is_lowercase_hex("ABC"));
  EXPECT_FALSE(is_lowercase_hex("ab_"));
}

TEST(Utf8PrefixTest, ACutNeverSplitsACharacter) {
  EXPECT_EQ(utf8_prefix("hello", 10), "hello");
  EXPECT_EQ(utf8_prefix("hello", 3), "hel");
  const std::string e = "\xC3\xA9";  // é, two bytes
  EXPECT_EQ(utf8_prefix("a" + e + "b", 2), "a");  // inside é: back to before it
  EXPECT_EQ(utf8_prefix("a" + e + "b", 3), "a" + e);
  const std::string euro = "\xE2\x82\xAC";  // three bytes
  EXPECT_EQ(utf8_prefix(euro + euro, 5), euro);
  EXPECT_EQ(utf8_prefix(euro, 0), "");
}

TEST(Utf8CheckTest, WellFormedCharactersPassAndEveryMalformedKindFails) {
  EXPECT_TRUE(is_utf8(""));
  EXPECT_TRUE(is_utf8("plain \xC3\xA9 \xE2\x82\xAC \xF0\x9F\x90\x84"));  // 1 to 4 bytes
  EXPECT_EQ(utf8_character_bytes("\xF0\x9F\x90\x84", 0), 4u);
  EXPECT_EQ(utf8_character_bytes(std::string(1, '\0'), 0), 1u);
  EXPECT_FALSE(is_utf8("\x80"));              // a continuation byte alone
  EXPECT_FALSE(is_utf8("\xE2\x82"));          // a sequence cut short
  EXPECT_FALSE(is_utf8("\xC0\xAF"));          // overlong '/'
  EXPECT_FALSE(is_utf8("\xED\xA0\x80"));      // a surrogate
  EXPECT_FALSE(is_utf8("\xF4\x90\x80\x80"));  // past U+10FFFF
  EXPECT_FALSE(is_utf8("\xFF"));
}

}  // namespace
}  // namespace farm
