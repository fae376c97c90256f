#include "renderer/loaders/token_count.h"

#include <emmintrin.h>

#include <bit>

namespace farm {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

}  // namespace

// 16 bytes at a time with SSE2, which every x86-64 has.
Tokens count_tokens(std::string_view text, bool digits_only) {
  Tokens out;
  out.bad = text.size();
  // A token starts at a non-space byte after a space (or at the text's start).
  const auto spaces_of = [](__m128i bytes) {
    const __m128i space = _mm_or_si128(_mm_or_si128(_mm_cmpeq_epi8(bytes, _mm_set1_epi8(' ')),
                                                    _mm_cmpeq_epi8(bytes, _mm_set1_epi8('\t'))),
                                       _mm_or_si128(_mm_cmpeq_epi8(bytes, _mm_set1_epi8('\n')),
                                                    _mm_cmpeq_epi8(bytes, _mm_set1_epi8('\r'))));
    return static_cast<unsigned>(_mm_movemask_epi8(space));
  };
  const auto non_digits_of = [](__m128i bytes) {
    // Digits are '0'..'9': bytes - '0' below 10 as unsigned, i.e. min(bytes - '0', 9) == bytes - '0'.
    const __m128i shifted = _mm_sub_epi8(bytes, _mm_set1_epi8('0'));
    const __m128i digit = _mm_cmpeq_epi8(_mm_min_epu8(shifted, _mm_set1_epi8(9)), shifted);
    return static_cast<unsigned>(_mm_movemask_epi8(digit)) ^ 0xFFFFu;
  };
  unsigned previous_space = 1;  // before the text: as after a space
  std::size_t i = 0;
  for (; i + 16 <= text.size(); i += 16) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(text.data() + i));
    const unsigned space = spaces_of(bytes);
    if (digits_only) {
      const unsigned bad = non_digits_of(bytes) & ~space;
      if (bad != 0) break;  // this block byte by byte below, up to its bad byte
    }
    const unsigned after_space = ((space << 1) | previous_space) & 0xFFFFu;
    out.count += static_cast<std::uint64_t>(std::popcount(~space & after_space & 0xFFFFu));
    previous_space = space >> 15;
  }
  // The tail, or the block with a bad byte.
  bool in_token = previous_space == 0;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (is_space(c)) {
      in_token = false;
      continue;
    }
    if (digits_only && (c < '0' || c > '9')) {
      out.bad = i;
      return out;
    }
    if (!in_token) ++out.count;
    in_token = true;
  }
  return out;
}

}  // namespace farm
