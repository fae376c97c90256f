// count_tokens (renderer/loaders/token_count.h), which counts a COLLADA file's array values and
// indices 16 bytes at a time, against the plain byte-by-byte count it replaced: every length
// around the block size, every mix of spaces, digits and other bytes, and the first bad byte.
#include "renderer/loaders/token_count.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

namespace farm {
namespace {

bool space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

Tokens byte_by_byte(std::string_view text, bool digits_only) {
  Tokens out;
  out.bad = text.size();
  bool in_token = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (space(text[i])) {
      in_token = false;
      continue;
    }
    if (digits_only && (text[i] < '0' || text[i] > '9')) {
      out.bad = i;
      return out;
    }
    if (!in_token) ++out.count;
    in_token = true;
  }
  return out;
}

TEST(TokenCount, AgreesWithAByteByByteCountOnRandomTexts) {
  std::mt19937 random(37);
  // Mostly digits and spaces, as index lists are; now and then a sign, a dot or a letter.
  const std::string alphabet = "0123456789 \t\n\r-.e";
  for (int round = 0; round < 20000; ++round) {
    const std::size_t length = random() % 70;
    const unsigned other_odds = 1 + random() % 40;  // one byte in this many is not a digit or space
    std::string text;
    for (std::size_t i = 0; i < length; ++i) {
      const bool other = random() % other_odds == 0;
      text += other ? alphabet[14 + random() % 3] : alphabet[random() % 14];
    }
    for (const bool digits_only : {false, true}) {
      const Tokens want = byte_by_byte(text, digits_only), got = count_tokens(text, digits_only);
      ASSERT_EQ(got.bad, want.bad) << "'" << text << "' digits_only " << digits_only;
      if (want.bad == text.size()) {
        ASSERT_EQ(got.count, want.count) << "'" << text << "'";
      }
    }
  }
}

TEST(TokenCount, TokensThatCrossBlocksCountOnce) {
  // A token across the 16-byte boundary, one starting right at it, one ending right before it.
  EXPECT_EQ(count_tokens("0123456789 12345678901 23", true).count, 3u);
  EXPECT_EQ(count_tokens("012345678901234 5 7", true).count, 3u);
  EXPECT_EQ(count_tokens(std::string(15, ' ') + "1" + std::string(16, ' ') + "2", true).count, 2u);
  EXPECT_EQ(count_tokens(std::string(40, '7'), true).count, 1u);
  EXPECT_EQ(count_tokens("", true).count, 0u);
  EXPECT_EQ(count_tokens("", true).bad, 0u);
}

TEST(TokenCount, TheFirstBadByteIsFoundWhereverItIs) {
  const std::string digits(50, '4');
  for (std::size_t at = 0; at < digits.size(); ++at) {
    std::string text = digits;
    text[at] = 'x';
    if (at + 5 < text.size()) text[at + 5] = '-';  // a later bad byte is not the one named
    EXPECT_EQ(count_tokens(text, true).bad, at);
    EXPECT_EQ(count_tokens(text, false).bad, text.size());  // values may be anything
  }
}

}  // namespace
}  // namespace farm
