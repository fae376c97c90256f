// The small text helpers several parts share: hex both ways (server/common/hex.h) and a UTF-8
// text cut without splitting a character (renderer/util/utf8_prefix.h).
#include <gtest/gtest.h>

#include "renderer/util/utf8_prefix.h"
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

}  // namespace
}  // namespace farm
